"""The clingo facade: errors with file and line, Python values, bounds, cores, costs."""

from __future__ import annotations

from pathlib import Path

import clingo
import pytest

from knowledge.asp import Asp, atom, facts, to_python
from knowledge.errors import AspError
from knowledge.sources import unsaved


def test_a_syntax_error_in_a_file_names_the_file_line_and_column(tmp_path: Path) -> None:
    path = tmp_path / "user.lp"
    path.write_text("a.\nb :- a\nc.\n")
    with pytest.raises(AspError, match=rf"^{path}:3:1: syntax error"):
        Asp().load(path)
    path.write_text("a.\nb :- c(.\n")
    with pytest.raises(AspError, match=rf"^{path}:2:8: syntax error"):
        Asp().load(path)


@pytest.mark.parametrize(
    ("text", "place", "character"),
    [("a :- é.\n", "1:6", "é"), ("a.\n%* é\n*%\nb :- a 📷.\n", "4:8", "📷")],
)
def test_a_character_beyond_ascii_outside_strings_and_comments_is_an_error_at_its_place(
    tmp_path: Path, text: str, place: str, character: str
) -> None:
    # clingo's lexer reports it with its bytes cut and the process aborts: never reach it
    path = tmp_path / "user.lp"
    path.write_text(text)
    with pytest.raises(AspError) as e:
        Asp().load(path)
    assert str(e.value) == f"{path}:{place}: unexpected character '{character}'"
    with pytest.raises(AspError, match=rf"^rules:{place}: unexpected character"):
        Asp().add(text, source="rules")
    path.write_text('% a comment with é\np("📷 \\" é").\n')  # in strings and comments
    Asp().load(path)


def test_an_editors_unsaved_program_is_read_from_its_buffer_and_named_as_its_file(
    tmp_path: Path,
) -> None:
    path = tmp_path / "user.lp"
    path.write_text("a.\n")
    with unsaved({path: "a.\n  b :- a c.\n"}), pytest.raises(AspError) as e:
        Asp().load(path)
    assert str(e.value) == f"{path}:2:10: syntax error, unexpected <IDENTIFIER>"
    Asp().load(path)  # the file itself is fine
    with unsaved({tmp_path / "new.lp": "p(1).\n"}):
        Asp().load(tmp_path / "new.lp")  # typed, never saved


def test_an_unsafe_rule_in_text_names_its_source_line_and_column() -> None:
    asp = Asp()
    asp.add("a.\np(X) :- a.\n", source="<rules>")
    with pytest.raises(AspError, match=r"^<program>:2:1: unsafe variables in: p\(X\)"):
        asp.ground()


def test_a_missing_file_and_bad_options_are_asp_errors(tmp_path: Path) -> None:
    with pytest.raises(AspError, match="cannot read"):
        Asp().load(tmp_path / "none.lp")
    with pytest.raises(AspError, match="invalid clingo options"):
        Asp(["--no-such-option"])


def test_symbols_become_python_values_and_back() -> None:
    asp = Asp()
    asp.add(
        facts([atom("p", 'a "quoted" name', 3, ("x", 1))])
        + "q(f(b), g).\n#show.\n#show p/3.\n#show q/2.\n"
    )
    asp.ground()
    answer = asp.solve().answers[0]
    assert answer.get("p") == [('a "quoted" name', 3, ("x", 1))]
    assert answer.get("q") == [(("f", "b"), "g")]
    assert to_python(clingo.Infimum) == "#inf"


def test_an_optimisation_keeps_the_best_model_with_its_cost() -> None:
    asp = Asp(["--opt-mode=opt"])
    asp.add("{ a(1..3) } >= 1. #minimize { X : a(X) }.")
    asp.ground()
    outcome = asp.solve(keep=False, costs=True)
    assert len(outcome.answers) == 1
    assert outcome.answers[0].get("a") == [(1,)] and outcome.answers[0].cost == (1,)
    assert outcome.exhausted


def test_assumptions_that_admit_no_model_come_back_as_a_core() -> None:
    asp = Asp(["0"])
    asp.add("#external e(1..3). { s }. :- e(1), s. :- e(2), not s.")
    asp.ground()
    for i in (1, 2, 3):
        asp.assign_external(atom("e", i), None)
    outcome = asp.solve(
        assumptions=[(atom("e", 1), True), (atom("e", 2), True), (atom("e", 3), True)]
    )
    assert outcome.satisfiable is False
    assert set(outcome.core) <= {atom("e", 1), atom("e", 2), atom("e", 3)}
    assert {atom("e", 1), atom("e", 2)} <= set(outcome.core)


def test_a_time_bound_interrupts_a_long_search() -> None:
    asp = Asp(["0"])
    asp.add("{ p(1..40) }.")
    asp.ground()
    asp.set("solve.models", "0")
    outcome = asp.solve(timeout=0.05, keep=False)
    assert outcome.interrupted and not outcome.exhausted
    assert outcome.satisfiable is True


def test_a_time_bound_never_cuts_short_a_later_solve_call() -> None:
    # bounds close to the search's own length: some alarms ring just as a search ends,
    # and their interrupt must not stop the unbounded call that follows
    asp = Asp(["0"])
    asp.add("{ p(1..3) }.")
    asp.ground()
    for i in range(300):
        asp.solve(timeout=i * 2e-6)
        outcome = asp.solve()
        assert outcome.exhausted and not outcome.interrupted and len(outcome.answers) == 8


def test_a_program_file_is_read_again_once_it_changed(tmp_path: Path) -> None:
    path = tmp_path / "rules.lp"
    path.write_text("a.\n")
    first = Asp()
    first.load(path)
    first.ground()
    path.write_text("b. c.\n")  # parsed once, kept while the file stays the same
    second = Asp()
    second.load(path)
    second.ground()
    assert first.solve().answers[0].atoms == {"a": [()]}
    assert second.solve().answers[0].atoms == {"b": [()], "c": [()]}
