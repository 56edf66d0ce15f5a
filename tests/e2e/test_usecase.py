"""The thesis use case end to end: a real ``dura run`` with its components, planner,
scheduler, observers, diagnosis and repair, driven through the ``dura_robot`` fixture
(the pytest plugin users test their own robots with).

Each test reads what happened from the executive's event log, not from timing. Robot
time runs ten times faster than the wall clock (``time_scale``), as in the robot's own
tests a user writes.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import psutil
import pytest

from executive.testing.harness import RobotProcess
from tests.conftest import USECASE, wait_for

pytestmark = pytest.mark.slow

Start = Callable[..., RobotProcess]
FAST = 10.0  # robot time ten times faster than the wall clock


def kinds(robot: RobotProcess, subject: str = "") -> list[str]:
    return [e.kind for e in robot.events() if subject in e.subject]


def gone(pid: int) -> bool:
    """The process ended (a zombie waiting for init to reap it counts as ended)."""
    try:
        return psutil.Process(pid).status() == psutil.STATUS_ZOMBIE
    except psutil.NoSuchProcess:
        return True


def first(events: list[dict[str, Any]], kind: str, subject: str = "") -> int:
    """The index of the first event of ``kind`` whose subject contains ``subject``."""
    return next(i for i, e in enumerate(events) if e.kind == kind and subject in e.subject)


def test_goals_are_planned_executed_and_achieved(dura_robot: Start) -> None:
    robot = dura_robot(USECASE, time_scale=FAST)
    pictures = robot.submit_goal("(and (picture_taken lab) (picture_taken office))")
    home = robot.submit_goal("(robot_at dock)")  # holds now, and must hold again at the end
    robot.wait_for(pictures, "achieved", timeout=90)
    robot.wait_for(home, "achieved", timeout=90)
    assert set(robot.facts("picture_taken")) == {"(picture_taken lab)", "(picture_taken office)"}
    dispatched = [e.subject for e in robot.events("DISPATCH")]
    assert "take_picture(lab)" in dispatched and "take_picture(office)" in dispatched


def test_a_failed_task_is_replanned_and_the_goal_achieved(dura_robot: Start) -> None:
    # a move takes 20 robot seconds (2 s of wall time): time to crash it on the way
    changes = {"behaviors": {"move_to": {"max_restarts": 0, "params": {"duration": 20.0}}}}
    robot = dura_robot(USECASE, changes=changes, time_scale=FAST)
    goal = robot.submit_goal("(robot_at lab)")
    assert wait_for(lambda: "START" in kinds(robot, "move_to"), 60)
    robot.inject_fault("move_to", "crash")
    robot.wait_for(goal, "achieved", timeout=90)
    events = robot.events()
    failed = first(events, "FAIL", "move_to")
    replanned = first(events[failed:], "REPLAN") + failed
    assert first(events[replanned:], "DISPATCH", "move_to(dock, lab)") >= 0
    assert robot.facts("robot_at") == ["(robot_at lab)"]


def test_an_unreachable_goal_is_reported_while_the_others_are_achieved(
    dura_robot: Start,
) -> None:
    robot = dura_robot(USECASE, time_scale=FAST)
    reachable = robot.submit_goal("(picture_taken lab)")
    unreachable = robot.submit_goal("(picture_taken dock)", priority=5)
    robot.wait_for(reachable, "achieved", timeout=90)
    goal = robot.wait_for(unreachable, "unreachable", timeout=10)
    assert goal.reason
    assert "(picture_taken dock)" not in robot.facts("picture_taken")


def test_a_critical_task_is_not_interrupted_by_replanning(dura_robot: Start) -> None:
    # a picture takes 30 robot seconds (3 s of wall time): time to add a goal meanwhile
    changes = {"behaviors": {"take_picture": {"params": {"duration": 30.0}}}}
    robot = dura_robot(USECASE, changes=changes, time_scale=FAST)
    first_goal = robot.submit_goal("(picture_taken lab)")
    assert wait_for(lambda: "START" in kinds(robot, "take_picture(lab)"), 60)
    second_goal = robot.submit_goal("(picture_taken office)")
    robot.wait_for(first_goal, "achieved", timeout=60)
    robot.wait_for(second_goal, "achieved", timeout=90)
    events = robot.events()
    started = first(events, "START", "take_picture(lab)")
    ended = first(events, "END", "take_picture(lab)")
    added = first(events, "GOAL_ADDED", "goal 2")
    assert started < added < ended
    between = [e.kind for e in events[added:ended] if "take_picture(lab)" in e.subject]
    assert "CANCEL" not in between and "FAIL" not in between
    replanned = [i for i, e in enumerate(events) if e.kind == "PLAN_START" and i > added]
    assert replanned and replanned[0] > ended  # the planner waited for the critical task


def test_a_killed_executive_restarts_and_continues_its_open_goals(dura_robot: Start) -> None:
    robot = dura_robot(USECASE, time_scale=FAST)
    goal = robot.submit_goal("(and (picture_taken office) (robot_at dock))")
    assert wait_for(lambda: "START" in kinds(robot, "move_to"), 60)
    pids = [c["pid"] for c in robot.request("component/list")["components"] if c["pid"]]
    assert pids
    robot.kill()
    assert wait_for(lambda: all(gone(p) for p in pids), 5.0)
    robot.start()  # returns once every service of it runs
    robot.wait_for(goal, "achieved", timeout=120)
    assert kinds(robot).count("EXECUTIVE_STARTED") == 2
    assert "(picture_taken office)" in robot.facts("picture_taken")


def test_functionalities_needed_by_later_steps_keep_running_between_the_steps(
    dura_robot: Start,
) -> None:
    robot = dura_robot(USECASE, time_scale=FAST)
    goal = robot.submit_goal("(and (picture_taken lab) (picture_taken office) (robot_at dock))")
    robot.wait_for(goal, "achieved", timeout=120)
    moves = [e for e in robot.events("DISPATCH") if e.subject.startswith("move_to")]
    assert len(moves) >= 2, moves  # move_to, take_picture, move_to, ...: lidar in between
    starts = [e.subject for e in robot.events("COMPONENT_STARTING")]
    for name in ("lidar", "lidar_filter", "robot_base", "cam"):
        assert starts.count(name) == 1, (name, starts)
    assert wait_for(
        lambda: all(
            c["state"] == "stopped"
            for c in robot.request("component/list")["components"]
            if c["component"] in ("lidar", "lidar_filter", "robot_base", "cam")
        ),
        10,
    )  # the plan has ended: nothing keeps them


def test_the_readme_example_waits_for_lidar_before_crashing_it(dura_robot: Start) -> None:
    # the planner-in-the-loop test of docs/how-to/testing.md, as written there (use case robot)
    robot: RobotProcess = dura_robot(USECASE, time_scale=10)
    goal = robot.submit_goal("(robot_at office)")
    robot.wait_for_component("lidar", "ready", timeout=60)  # started for the drive
    robot.inject_fault("lidar", "crash")  # any mode of the fault injection table
    robot.wait_for(goal, "achieved", timeout=90)  # else: the reason and the latest events
    assert robot.facts("robot_at") == ["(robot_at office)"]
    restarted = robot.wait_for_event("REPAIR", "lidar", timeout=30)
    assert restarted.data["restart"] is True
