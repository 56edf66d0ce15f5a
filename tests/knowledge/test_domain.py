"""Reading PDDL through unified-planning, with errors that name file and line."""

from __future__ import annotations

from pathlib import Path

import pytest

from knowledge.domain import parse_problem, read_domain
from knowledge.errors import DomainError
from tests.conftest import ROOT

DOMAIN = ROOT / "domains" / "usecase" / "domain.pddl"


def test_the_use_case_domain_has_durative_actions_with_typed_parameters() -> None:
    info = read_domain(DOMAIN)
    assert info.name == "usecase"
    move_to = info.actions["move_to"]
    assert move_to.durative
    assert move_to.parameters == (("from", "place"), ("to", "place"))
    assert move_to.line is not None
    assert "(:durative-action move_to" in DOMAIN.read_text().splitlines()[move_to.line - 1]
    assert info.predicates["connected"] == ("place", "place")
    assert info.functions["travel_time"] == ("place", "place")
    assert info.types == ("place",)


def test_an_empty_functions_block_is_accepted(tmp_path: Path) -> None:
    path = tmp_path / "d.pddl"
    path.write_text(
        "(define (domain d) (:requirements :strips :typing)\n (:types t)\n"
        " (:predicates (p ?x - t))\n (:functions )\n"
        " (:action a :parameters (?x - t) :precondition (p ?x) :effect (not (p ?x))))"
    )
    assert list(read_domain(path).actions) == ["a"]


def test_a_syntax_error_names_the_line(tmp_path: Path) -> None:
    path = tmp_path / "d.pddl"
    path.write_text(
        "(define (domain d)\n (:requirements :strips)\n (:predicates (p)\n (:action a))\n"
    )
    with pytest.raises(DomainError) as error:
        read_domain(path)
    assert str(error.value) == (
        f"{path}:3:2: '(:predicates' is not closed before '(:action' at line 4 (a ')' is missing)"
    )
    assert error.value.excerpt == "    3 |  (:predicates (p)\n      |  ^"


def test_an_unreadable_file_is_named(tmp_path: Path) -> None:
    with pytest.raises(DomainError, match=r"nope\.pddl: cannot read"):
        read_domain(tmp_path / "nope.pddl")


def test_a_problem_is_parsed_against_the_domain_and_its_errors_name_the_problem() -> None:
    problem = parse_problem(DOMAIN, (ROOT / "examples/usecase/problem.pddl").read_text())
    assert {o.name for o in problem.all_objects} == {"dock", "lab", "office"}
    bad = "(define (problem p) (:domain usecase)\n (:objects a - place)\n (:init (robot_at b)))"
    with pytest.raises(DomainError, match=r"^world.pddl:3:19: unknown object 'b'$"):
        parse_problem(DOMAIN, bad, "world.pddl")


def test_a_durative_action_keeps_its_duration_as_written_and_an_instant_one_has_none(
    tmp_path: Path,
) -> None:
    assert read_domain(DOMAIN).actions["move_to"].duration == (
        "(= ?duration (travel_time ?from ?to))"
    )
    path = tmp_path / "d.pddl"
    path.write_text(
        "(define (domain d) (:requirements :strips :typing :durative-actions)\n"
        " (:types t)\n (:predicates (p ?x - t))\n"
        " (:durative-action slow :parameters (?x - t) ; (not the duration)\n"
        "   :duration (and (>= ?duration 2)   ; a comment (with parentheses\n"
        "                  (<= ?duration 5))\n"
        "   :condition (at start (p ?x)) :effect (at end (not (p ?x))))\n"
        " (:action quick :parameters (?x - t) :precondition (p ?x) :effect (not (p ?x))))"
    )
    actions = read_domain(path).actions
    assert actions["slow"].duration == "(and (>= ?duration 2) (<= ?duration 5))"
    assert actions["quick"].duration is None


def test_an_object_named_like_its_type_is_accepted_as_rosplan_writes_it(tmp_path: Path) -> None:
    from tests.executive.planning.planning_cases import DRIVERLOG_DOMAIN, DRIVERLOG_PROBLEM

    domain = tmp_path / "driverlog.pddl"
    domain.write_text(DRIVERLOG_DOMAIN)
    problem = parse_problem(domain, DRIVERLOG_PROBLEM, "drive1.pddl")
    assert {o.name: str(o.type) for o in problem.all_objects} == {
        "driver": "driver", "truck": "truck", "depot": "location", "market": "location"
    }  # fmt: skip


def test_a_name_declared_twice_is_still_refused_at_its_second_line(tmp_path: Path) -> None:
    from tests.executive.planning.planning_cases import DRIVERLOG_DOMAIN, DRIVERLOG_TWICE

    domain = tmp_path / "driverlog.pddl"
    domain.write_text(DRIVERLOG_DOMAIN)
    with pytest.raises(DomainError, match=r"^twice\.pddl:6:5: name 'depot' is declared twice$"):
        parse_problem(domain, DRIVERLOG_TWICE, "twice.pddl")


def test_a_predicate_declared_twice_is_refused_at_its_second_line(tmp_path: Path) -> None:
    domain = tmp_path / "twice.pddl"
    domain.write_text(
        "(define (domain twice)\n  (:requirements :strips)\n  (:predicates\n"
        "    (ready)\n    (ready)))\n"
    )
    with pytest.raises(DomainError, match=r"twice\.pddl:5:6: name 'ready' is declared twice"):
        read_domain(domain)


HIERARCHY = """(define (domain hier)
  (:requirements :strips :typing :durative-actions)
  (:types driver truck - locatable place)
  (:predicates (at ?x - locatable ?p - place))
  (:durative-action drive
    :parameters (?t - truck ?d - driver ?a ?b - place)
    :duration (= ?duration 3)
    :condition (and (at start (at ?t ?a)) (over all (at ?d ?a)))
    :effect (and (at start (not (at ?t ?a))) (at end (at ?t ?b)))))
"""


def test_subtypes_are_named_by_their_names_not_by_how_unified_planning_prints_them(
    tmp_path: Path,
) -> None:
    path = tmp_path / "d.pddl"
    path.write_text(HIERARCHY)
    info = read_domain(path)
    assert set(info.types) == {"locatable", "driver", "truck", "place"}
    assert info.supertypes["driver"] == "locatable"
    assert info.supertypes["locatable"] is None
    assert info.actions["drive"].parameters[:2] == (("t", "truck"), ("d", "driver"))
    assert info.predicates["at"] == ("locatable", "place")
    problem = parse_problem(
        path,
        "(define (problem p) (:domain hier) (:objects d1 - driver a - place)"
        " (:init (at d1 a)) (:goal (at d1 a)))",
    )
    from executive.planning.problem import world_of

    assert world_of(problem).objects == {"d1": "driver", "a": "place"}
