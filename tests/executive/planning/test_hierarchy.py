"""A domain with a type hierarchy three levels deep, through every place that checks a
type: offline planning, validation, ``dura domain show|check``, goals, task arguments,
sensing rules and integrity goals. Objects of subtypes stand where a predicate or an
action wants the supertype; objects are named like their types (``robot - robot``)."""

from __future__ import annotations

from pathlib import Path

import pytest

from executive.planning.expression import Signature, parse
from executive.planning.problem import read_world
from executive.tasks.arguments import check_objects
from knowledge.domain import DomainInfo, read_domain
from knowledge.errors import DomainError, KnowledgeError
from knowledge.robot import load_robot
from knowledge.validation import validate
from tests.conftest import run_dura
from tests.executive.planning.planning_cases import warehouse_robot


@pytest.fixture
def warehouse(tmp_path: Path) -> Path:
    return warehouse_robot(tmp_path / "warehouse")


def domain_of(robot: Path) -> DomainInfo:
    return read_domain(robot.parent / "domain.pddl")


def test_a_type_is_a_kind_of_each_of_its_ancestors_and_of_nothing_else(warehouse: Path) -> None:
    domain = domain_of(warehouse)
    assert domain.is_a("robot", "vehicle")
    assert domain.is_a("robot", "locatable")  # two levels up
    assert domain.is_a("fragile", "locatable")
    assert domain.is_a("dock", "object")
    assert not domain.is_a("vehicle", "robot")
    assert not domain.is_a("dock", "locatable")
    objects = {"robot": "robot", "t1": "truck", "vase": "fragile", "dock": "dock"}
    assert domain.objects_of("vehicle", objects) == ["robot", "t1"]
    assert domain.objects_of("locatable", objects) == ["robot", "t1", "vase"]
    assert domain.objects_of("place", objects) == ["dock"]


def test_the_warehouse_plans_offline_with_objects_of_subtypes(warehouse: Path) -> None:
    folder = warehouse.parent
    done = run_dura("plan", "--offline", "domain.pddl", "problem.pddl", cwd=folder)
    assert done.returncode == 0, done.stderr
    assert "drive(robot, dock, store)" in done.stdout  # a robot where a vehicle is wanted
    assert "drop(robot, parcel, lab)" in done.stdout


def test_the_warehouse_robot_validates_and_its_domain_shows_each_type_with_its_parent(
    warehouse: Path,
) -> None:
    result = validate(warehouse)
    assert [str(f) for f in result.findings] == []
    done = run_dura("domain", "show", "--offline", "--robot", "robot.yaml", cwd=warehouse.parent)
    assert done.returncode == 0, done.stderr
    rows = {tuple(line.split()) for line in done.stdout.splitlines()}
    assert {("robot", "vehicle"), ("vehicle", "locatable"), ("fragile", "crate")} <= rows
    assert ("dock", "place") in rows
    assert not any(" - " in line.split("  ")[0] for line in done.stdout.splitlines())


def test_dura_domain_check_takes_a_subtype_of_a_type_in_use_as_used(warehouse: Path) -> None:
    # nothing names truck or fragile, but a truck is a vehicle and a fragile crate a crate
    done = run_dura("domain", "check", "domain.pddl", "problem.pddl", cwd=warehouse.parent)
    assert done.returncode == 0, done.stderr
    assert "not used" not in done.stdout + done.stderr


def test_a_goal_names_objects_of_subtypes_where_the_predicate_wants_the_supertype(
    warehouse: Path,
) -> None:
    domain = domain_of(warehouse)
    world, _ = read_world(warehouse.parent / "domain.pddl", warehouse.parent / "problem.pddl")
    signature = Signature.of(domain, {**world.objects, "vase": "fragile"})
    assert str(parse("(and (at vase lab) (at robot dock))", signature)) == (
        "(and (at vase lab) (at robot dock))"
    )
    with pytest.raises(DomainError) as wrong_type:
        parse("(holding robot dock)", signature)
    assert str(wrong_type.value) == (
        "goal '(holding robot dock)': argument 2 of 'holding' must be a crate, but 'dock' is a dock"
    )
    with pytest.raises(DomainError) as arity:
        parse("(at vase)", signature)
    assert str(arity.value) == (
        "goal '(at vase)': 'at' takes 2 arguments (?x - locatable ?p - place), not 1"
    )


def test_a_task_typed_by_a_supertype_accepts_an_object_of_a_subtype(warehouse: Path) -> None:
    robot = load_robot(warehouse)
    domain = domain_of(warehouse)
    objects = {"robot": "robot", "dock": "dock", "store": "place", "vase": "fragile"}
    check_objects(robot.tasks["pick"], {"crate": "vase", "place": "dock"}, domain, objects)
    with pytest.raises(KnowledgeError) as refused:
        check_objects(robot.tasks["pick"], {"crate": "robot", "place": "dock"}, domain, objects)
    assert str(refused.value) == (
        "task 'pick': crate=robot: 'robot' is a robot, not of type 'crate' "
        "(objects of that type: vase)"
    )


def test_sensing_rules_and_integrity_goals_name_objects_of_subtypes(warehouse: Path) -> None:
    text = warehouse.read_text().replace("fact: (battery_low)", "fact: (at robot dock)")
    warehouse.write_text(text)
    assert [str(f) for f in validate(warehouse).findings] == []
    warehouse.write_text(text.replace("fact: (at robot dock)", "fact: (at dock robot)"))
    messages = [f.message for f in validate(warehouse).errors]
    assert messages == [
        "sensing rule 'battery_low': argument 1 of 'at' must be a locatable, but 'dock' is a dock"
    ]
