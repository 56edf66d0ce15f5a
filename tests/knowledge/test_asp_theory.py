"""The clingo facade with a theory (clingo-dl), fast facts, level priorities, cores of
many assumptions, and a grace period for a first model."""

from __future__ import annotations

from pathlib import Path

import pytest
from clingodl import ClingoDLTheory

from knowledge.asp import Asp, atom
from knowledge.errors import AspError

ORDER = """
task(a;b).
duration(a,3). duration(b,5).
1 { first(X) : task(X) } 1.
&diff{ s(X) - s(Y) } <= -D :- first(X), task(Y), X != Y, duration(X,D).
&diff{ 0 - s(X) } <= 0 :- task(X).
#minimize{ 1,X : first(X), X = b }.
#show first/1.
"""


def test_a_program_with_difference_constraints_is_solved_with_the_clingo_dl_theory(
    tmp_path: Path,
) -> None:
    program = tmp_path / "order.lp"
    program.write_text(ORDER)
    asp = Asp(["--models=0"], theory=ClingoDLTheory())  # type: ignore[no-untyped-call]
    asp.load(program)
    asp.ground()
    outcome = asp.solve(costs=True)
    assert outcome.exhausted
    assert outcome.answers[-1].get("first") == [("a",)]
    assert (outcome.answers[-1].cost, outcome.answers[-1].priority) == ((0,), (0,))


def test_a_syntax_error_in_a_theory_program_names_its_file_and_line(tmp_path: Path) -> None:
    program = tmp_path / "bad.lp"
    program.write_text("a.\n&diff{ s(X) - } <= 1 :- a.\n")
    with pytest.raises(AspError, match=r"bad\.lp:2:15: syntax error"):
        Asp(theory=ClingoDLTheory()).load(program)  # type: ignore[no-untyped-call]


def test_program_text_for_a_theory_keeps_its_line_numbers_and_columns() -> None:
    asp = Asp(theory=ClingoDLTheory())  # type: ignore[no-untyped-call]
    with pytest.raises(AspError, match=r"^rules:3:8: syntax error"):
        asp.add("a.\nb.\nc :- a b.\n", source="rules")
    # and the columns of its first line, although clingo read a head before it
    with pytest.raises(AspError, match=r"^rules:1:8: syntax error"):
        asp.add("c :- a b.\n", source="rules")


def test_facts_are_added_without_the_theory_and_ground_with_the_program() -> None:
    asp = Asp(theory=ClingoDLTheory())  # type: ignore[no-untyped-call]
    asp.add_facts([atom("duration", 'a quoted "name"', 3)])
    asp.add("&diff{ s(X) - 0 } <= D :- duration(X,D).\n#show duration/2.")
    asp.ground()
    assert asp.solve().answers[0].get("duration") == [('a quoted "name"', 3)]


def test_an_unsatisfiable_core_names_the_assumptions_in_it_among_many_atoms() -> None:
    asp = Asp()
    asp.add("{ p(1..4) }. :- p(1), p(3). q(1..1000).")
    asp.ground()
    assumptions = [(atom("p", i), True) for i in range(1, 5)]
    outcome = asp.solve(assumptions=assumptions)
    assert outcome.satisfiable is False
    assert {atom("p", 1), atom("p", 3)} <= set(outcome.core) <= set(dict(assumptions))


def test_a_first_model_ends_the_search_when_the_timeout_passed_without_one() -> None:
    asp = Asp(["--opt-strategy=bb"])
    asp.add("{ a(1..40) }. #maximize{ X : a(X) }.")
    asp.ground()
    outcome = asp.solve(timeout=0.0, grace=30.0)
    assert outcome.satisfiable is True
    assert outcome.answers


def test_program_text_for_a_theory_goes_to_its_part_with_parameters() -> None:
    asp = Asp(theory=ClingoDLTheory())  # type: ignore[no-untyped-call]
    asp.add("step(n). &diff{ s(n) - 0 } <= n. #show step/1.", part="step", params=["n"])
    asp.ground([("step", [7])])
    assert asp.solve().answers[0].get("step") == [(7,)]
