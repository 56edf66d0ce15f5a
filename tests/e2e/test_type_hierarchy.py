"""A robot whose domain has a type hierarchy three levels deep (the warehouse: a robot is
a vehicle is a locatable, a fragile crate is a crate): a real ``dura run`` with its
components and planner plans and executes with objects of subtypes, takes an object of
a subtype added at run time, and replans for it. Robot time runs ten times faster."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import pytest

from executive.testing.harness import RobotProcess
from tests.conftest import run_dura
from tests.executive.planning.planning_cases import warehouse_robot

pytestmark = pytest.mark.slow

FAST = 10.0
Start = Callable[..., RobotProcess]


def test_a_robot_with_subtypes_replans_for_an_object_of_a_subtype_added_at_run_time(
    dura_robot: Start, tmp_path: Path
) -> None:
    robot = dura_robot(warehouse_robot(tmp_path / "warehouse"), time_scale=FAST)
    parcel = robot.submit_goal("(at parcel lab)")  # robot - robot drives as a vehicle
    robot.wait_for(parcel, "achieved", timeout=120)

    misspelt = run_dura("object", "add", "vase", "fragil", cwd=robot.folder)
    assert misspelt.returncode == 1
    assert misspelt.stderr.splitlines() == ["dura: unknown type 'fragil' (did you mean 'fragile'?)"]
    root = run_dura("object", "add", "vase", "object", cwd=robot.folder)
    assert root.returncode == 1  # the planner could take no object of the root type
    assert root.stderr.splitlines() == [
        "dura: an object needs a type of the domain, not 'object' (the domain's types: crate, "
        "dock, fragile, locatable, place, robot, truck, vehicle)"
    ]
    assert robot.events("OBJECT_ADDED") == []  # nothing stored

    added = run_dura("object", "add", "vase", "fragile", cwd=robot.folder)
    assert added.returncode == 0, added.stderr
    assert added.stdout.strip() == "object vase - fragile added"
    arity = run_dura("goal", "add", "(at vase)", cwd=robot.folder)
    assert arity.returncode == 1
    assert arity.stderr.splitlines() == [
        "dura: goal '(at vase)': 'at' takes 2 arguments (?x - locatable ?p - place), not 1"
    ]
    assert [g.id for g in robot.goals()] == [parcel]  # nothing stored
    robot.set_fact("(at vase lab)")  # a fragile crate where a locatable is wanted
    vase = robot.submit_goal("(at vase dock)")  # and a dock where a place is wanted
    robot.wait_for(vase, "achieved", timeout=120)

    ended = [e.subject for e in robot.events("END")]
    assert "pick(robot, vase, lab)" in ended, ended
    assert "drop(robot, vase, dock)" in ended, ended
    assert "(at vase dock)" in robot.facts("at")
    state = run_dura("state", "get", "at", cwd=robot.folder)
    assert state.returncode == 0, state.stderr
    assert "(at vase dock)" in state.stdout
