"""Goal and condition expressions: read against the domain, evaluated over facts."""

from __future__ import annotations

import pytest

from executive.planning.expression import (
    And,
    Arith,
    Atom,
    Compare,
    Const,
    FactPattern,
    Value,
    WorldState,
    atoms,
    is_name,
    named_objects,
    parse,
    parse_fact,
)
from knowledge.errors import DomainError
from knowledge.records import Fact
from tests.executive.planning.planning_cases import expr, signature

REFUSED = [
    ("(picture_taken lob)", "unknown object 'lob' (did you mean 'lab'?)"),
    ("(pictur_taken lab)", "unknown predicate 'pictur_taken' (did you mean 'picture_taken'?)"),
    ("(picture_taken lab office)", "'picture_taken' takes 1 argument (?p - place), not 2"),
    ("(and (picture_taken lab)", "missing ')'"),
    ("(travel_time dock lab)", "'travel_time' is a function (a number)"),
    ("(exists (?p - plac) (robot_at ?p))", "unknown type 'plac' (did you mean 'place'?)"),
    ("(robot_at ?x)", "unbound variable '?x'"),
    ("", "it is empty"),
    ("(>= (robot_at dock) 1)", "'robot_at' is a predicate, not a number"),
]


@pytest.mark.parametrize(("text", "reason"), REFUSED)
def test_a_goal_that_does_not_fit_the_domain_is_refused_with_the_reason(
    text: str, reason: str
) -> None:
    with pytest.raises(DomainError) as e:
        parse(text, signature())
    assert str(e.value).startswith(f"goal '{text}': {reason}")


def test_an_object_of_the_wrong_type_is_refused() -> None:
    sig = signature()
    typed = type(sig)(sig.predicates, sig.functions, {**sig.objects, "r1": "robot"}, sig.parents)
    with pytest.raises(
        DomainError, match="argument 1 of 'robot_at' must be a place, but 'r1' is a robot"
    ):
        parse("(robot_at r1)", typed)


def test_quantifiers_expand_over_the_objects_of_their_type() -> None:
    goal = expr("(forall (?p - place) (imply (photographable ?p) (picture_taken ?p)))")
    assert atoms(goal) == {
        (name, (p,))
        for p in ("dock", "lab", "office")
        for name in ("photographable", "picture_taken")
    }
    state = WorldState([Fact("photographable", ("lab",)), Fact("picture_taken", ("lab",))])
    assert state.holds(goal)
    assert not WorldState([Fact("photographable", ("lab",))]).holds(goal)


def test_numeric_comparisons_read_the_facts_and_an_unknown_number_is_false() -> None:
    goal = expr("(and (robot_at dock) (< (+ (travel_time dock lab) 1) 6))")
    travel = Arith("+", (Value("travel_time", ("dock", "lab")), Const(1.0)))
    assert goal == And((Atom("robot_at", ("dock",)), Compare("<", travel, Const(6.0))))
    facts = [Fact("robot_at", ("dock",)), Fact("travel_time", ("dock", "lab"), 4.0)]
    assert WorldState(facts).holds(goal)
    assert not WorldState(facts[:1]).holds(goal)


def test_facts_are_read_as_atoms_negations_and_numbers() -> None:
    sig = signature()
    assert parse_fact("(robot_at lab)", sig) == Fact("robot_at", ("lab",), True)
    assert parse_fact("(not (robot_at lab))", sig) == Fact("robot_at", ("lab",), False)
    assert parse_fact("(= (travel_time dock lab) 7.5)", sig) == Fact(
        "travel_time", ("dock", "lab"), 7.5
    )
    with pytest.raises(DomainError, match=r"^fact '\(and\)': expected a predicate"):
        parse_fact("(and)", sig)


def test_expressions_print_as_pddl() -> None:
    text = "(and (robot_at dock) (or (picture_taken lab) (not (picture_taken office))))"
    assert str(expr(text)) == text


def test_the_objects_an_expression_names_are_its_arguments_not_its_words() -> None:
    text = (
        "(and (robot_at lab) (forall (?p - place) (picture_taken ?p)) "
        "(>= (travel_time dock office) 2) (not (= ?x hall)))"
    )
    assert named_objects(text) == {"lab", "dock", "office", "hall"}
    assert named_objects("(picture_taken lab") == frozenset()  # not an expression


@pytest.mark.parametrize(
    ("name", "ok"),
    [("hall", True), ("hall-2_b", True), ("2hall", False), ("a b", False), ("", False)],
)
def test_a_pddl_name_is_a_letter_then_letters_digits_hyphens_or_underscores(
    name: str, ok: bool
) -> None:
    assert is_name(name) is ok


def test_a_fact_pattern_matches_a_name_and_leading_arguments() -> None:
    facts = [Fact("robot_at", ("dock",)), Fact("travel_time", ("dock", "lab"), 3.0)]
    for text, matched in [
        ("", facts),
        ("robot_at", facts[:1]),
        ("(robot_at *)", facts[:1]),
        ("(travel_time dock *)", facts[1:]),
        ("travel_time lab", []),
        ("(* dock)", facts),
    ]:
        pattern = FactPattern.read(text)
        pattern.check(signature())
        assert [f for f in facts if pattern.matches(f)] == matched, text


@pytest.mark.parametrize(
    ("text", "reason"),
    [
        ("(robot_at (lab))", "expected a name or *, not (lab)"),
        ("(robot_at", "missing ')'"),
        ("(robot_a *)", "unknown predicate or function 'robot_a' (did you mean 'robot_at'?)"),
        ("(robot_at lob)", "unknown object 'lob' (did you mean 'lab'?)"),
        ("(robot_at dock lab)", "'robot_at' takes 1 argument (?p - place), not 2"),
    ],
)
def test_a_fact_pattern_that_does_not_fit_the_domain_is_refused(text: str, reason: str) -> None:
    with pytest.raises(DomainError) as e:
        FactPattern.read(text).check(signature())
    assert str(e.value).startswith("fact pattern '") and str(e.value).endswith(reason)
