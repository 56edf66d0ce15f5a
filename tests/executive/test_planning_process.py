"""The high level in a process of its own (``dura run --only planning``) beside an
executive that runs without it: plans are made there and carried out by the
executive's task executor, over the bus."""

from __future__ import annotations

import contextlib
import json
from collections.abc import Iterator
from pathlib import Path

import pytest

from executive.bus.api.planning import STATUS
from executive.bus.keys import service_alive
from executive.testing.harness import RobotProcess, ServiceGroupProcess, robot_variant
from knowledge.records import Event, GoalState
from tests.conftest import USECASE, nobody_answers, run_dura, wait_for

pytestmark = pytest.mark.slow

FAST = 10.0  # robot time ten times faster than the wall clock
WITHOUT_PLANNING = ["--without", "planning"]


@contextlib.contextmanager
def split(description: Path, folder: Path) -> Iterator[RobotProcess]:
    """The executive without planning, and the planning process beside it."""
    with (
        RobotProcess(description, folder, run_args=WITHOUT_PLANNING, time_scale=FAST) as robot,
        ServiceGroupProcess(robot, "planning"),
    ):
        yield robot


def first(events: list[Event], kind: str, subject: str = "") -> int:
    """The index of the first event of ``kind`` whose subject contains ``subject``."""
    return next(i for i, e in enumerate(events) if e.kind == kind and subject in e.subject)


def test_a_goal_is_planned_in_the_planning_process_and_executed_by_the_executive(
    tmp_path: Path,
) -> None:
    with RobotProcess(USECASE, tmp_path, run_args=WITHOUT_PLANNING, time_scale=FAST) as robot:
        env = robot.environment()
        assert nobody_answers(robot.bus, STATUS)  # the planning process answers it
        with ServiceGroupProcess(robot, "planning"):
            assert robot.bus.alive(service_alive("planning"))
            added = run_dura("goal", "add", "(picture_taken lab)", "--json", cwd=tmp_path, env=env)
            assert added.returncode == 0, added.stderr
            goal = int(json.loads(added.stdout)["id"])
            robot.wait_for(goal, "achieved", timeout=90)
            status = run_dura("status", "--json", cwd=tmp_path, env=env)
            assert status.returncode == 0, status.stderr
            answer = json.loads(status.stdout)
            assert "take_picture" in json.dumps(answer["tasks"])  # the executive's tasks
            assert {c["component"] for c in answer["components"]} >= {"cam", "take_picture"}
            # the executive's task executor ran the step, for the plan of the other process
            tasks = robot.events("TASK_SUCCEEDED")
            assert any("take_picture(lab)" in e.subject for e in tasks)
            assert robot.facts("picture_taken") == ["(picture_taken lab)"]
        assert nobody_answers(robot.bus, STATUS)  # the planning process answered it
    assert "planning of robot 'usecase': runs" in (tmp_path / "planning.log").read_text()


def test_a_step_failing_in_the_executive_is_replanned_in_the_planning_process(
    tmp_path: Path,
) -> None:
    # a move takes 20 robot seconds (2 s of wall time): time to crash it on the way
    changes = {"behaviors": {"move_to": {"max_restarts": 0, "params": {"duration": 20.0}}}}
    description = robot_variant(USECASE, tmp_path / "description", changes)
    with split(description, tmp_path) as robot:
        goal = robot.submit_goal("(robot_at lab)")
        assert wait_for(lambda: robot.events("TASK_STARTED") != [], 60)
        robot.inject_fault("move_to", "crash")
        robot.wait_for(goal, "achieved", timeout=90)
        events = robot.events()
        failed = first(events, "TASK_FAILED", "move_to")
        replanned = first(events[failed:], "REPLAN") + failed
        assert first(events[replanned:], "DISPATCH", "move_to(dock, lab)") >= 0
        assert robot.facts("robot_at") == ["(robot_at lab)"]


def test_a_step_the_plan_cancels_ends_in_the_executive_and_reports_nothing_more(
    tmp_path: Path,
) -> None:
    changes = {"behaviors": {"move_to": {"params": {"duration": 40.0}}}}
    description = robot_variant(USECASE, tmp_path / "description", changes)
    with split(description, tmp_path) as robot:
        far = robot.submit_goal("(robot_at lab)")
        assert wait_for(lambda: robot.events("TASK_STARTED") != [], 60)
        robot.cancel_goal(far)  # its plan cancels the move it runs
        cancelled = robot.wait_for_event("TASK_CANCELLED", "move_to", timeout=30)
        assert cancelled.data["reason"] == "the plan no longer needs it"
        # a later round of the planner: by then a report of the move would have come
        later = robot.submit_goal("(picture_taken dock)")
        ended = (GoalState.ACHIEVED, GoalState.UNREACHABLE, GoalState.FAILED)
        assert wait_for(lambda: robot.goal(later).state in ended, 90)
        assert robot.goal(far).state is GoalState.CANCELLED
        kinds = [e.kind for e in robot.events() if "move_to(dock, lab)" in e.subject]
        assert "CANCEL" in kinds and "FAIL" not in kinds
