"""A world model that senses itself, goals that keep up with it, plans watched ahead:
real ``dura run`` processes with their components and planner, robot time ten times
faster than the wall clock.

Each test reads what happened from the executive's event log, not from timing.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import pytest

from executive.testing.harness import RobotProcess
from knowledge.records import Event, GoalState
from tests.conftest import ROOT, USECASE, run_dura

pytestmark = pytest.mark.slow

TRANSPORT = ROOT / "examples" / "transport" / "robot.yaml"
FAST = 10.0  # robot time runs ten times faster than the wall clock
Start = Callable[..., RobotProcess]


def index(events: list[Event], kind: str, subject: str = "", **data: Any) -> int:
    """The index of the first event of ``kind`` about ``subject`` whose data has ``data``."""
    return next(
        i
        for i, e in enumerate(events)
        if e.kind == kind
        and subject in e.subject
        and all(e.data.get(k) == v for k, v in data.items())
    )


def test_a_sensing_rule_sets_a_fact_from_a_topic_and_the_integrity_goal_follows(
    dura_robot: Start,
) -> None:
    # the base drains its battery while it drives; the sensing rule of robot.yaml turns
    # a level under 20 % into (battery_low), and the recharge integrity goal follows
    battery = {"battery": 22.5, "drain": 1.0, "charge_rate": 40.0}
    changes = {"functionalities": {"base": {"params": battery}}}
    robot = dura_robot(TRANSPORT, changes=changes, time_scale=FAST)
    delivery = robot.submit_goal("(crate_at parcel lab)")
    sensed = robot.wait_for_event("STATE_SET", "(battery_low)", timeout=120)
    assert sensed.data["source"] == "sensing"
    assert sensed.data["rule"] == "battery_low"
    assert sensed.data["topic"] == "battery"
    assert sensed.data["value"] < 20
    posted = robot.wait_for_event("INTEGRITY_GOAL", "recharge", after=sensed.id, timeout=60)
    robot.wait_for(posted.data["goal"], "achieved", timeout=120)
    robot.wait_for(delivery, "achieved", timeout=120)
    assert robot.facts("battery_low") == []
    assert "(crate_at parcel lab)" in robot.facts("crate_at")


def test_an_unreachable_goal_becomes_reachable_after_dura_state_set_and_is_achieved(
    dura_robot: Start,
) -> None:
    robot = dura_robot(USECASE, time_scale=FAST)
    goal = robot.submit_goal("(picture_taken dock)")
    unreachable = robot.wait_for(goal, "unreachable", timeout=60)
    # the reason names what is missing, not only that the planner found nothing
    assert (
        "(picture_taken dock) cannot become true: take_picture(dock) needs (photographable dock)"
        in unreachable.reason
    ), unreachable.reason
    done = run_dura("state", "set", "(photographable dock)", cwd=robot.folder)
    assert done.returncode == 0, done.stderr
    robot.wait_for(goal, "achieved", timeout=60)
    events = robot.events()
    reposted = index(events, "GOAL_PENDING", f"goal {goal}")
    assert (
        "reachable again after STATE_SET (photographable dock)" in (events[reposted].data["reason"])
    )
    assert index(events, "STATE_SET", "(photographable dock)") < reposted
    assert "(picture_taken dock)" in robot.facts("picture_taken")


def test_a_maintenance_goal_is_reposted_once_it_stops_holding_and_achieved_again(
    dura_robot: Start,
) -> None:
    robot = dura_robot(USECASE, time_scale=FAST)
    home = robot.submit_goal("(robot_at dock)", keep=True)
    robot.wait_for(home, "achieved", timeout=60)  # holds already: achieved, and watched
    listed = run_dura("goal", "list", cwd=robot.folder)
    assert "achieved, watched" in listed.stdout and "keep" in listed.stdout, listed.stdout
    pictures = robot.submit_goal("(picture_taken lab)")
    robot.wait_for(pictures, "achieved", timeout=90)
    reposted = robot.wait_for_event("GOAL_PENDING", f"goal {home}", timeout=60)
    assert reposted.data["reason"].startswith(
        "maintenance goal: (robot_at dock) no longer holds"
    ), reposted.data
    robot.wait_for_event("GOAL_ACHIEVED", f"goal {home}", after=reposted.id, timeout=90)
    assert robot.goal(home).state is GoalState.ACHIEVED
    assert robot.facts("robot_at") == ["(robot_at dock)"]
    shown = run_dura("goal", "show", str(home), cwd=robot.folder)
    assert "maintenance goal" in shown.stdout
    assert "watched and posted again whenever it stops holding" in shown.stdout


def test_a_road_blocked_ahead_replans_before_the_robot_gets_there(dura_robot: Start) -> None:
    # drives take 30 robot seconds (3 s of wall time): time to block a road ahead
    slow = {"behaviors": {"drive_to": {"params": {"duration": 30.0}}}}
    robot = dura_robot(TRANSPORT, changes=slow, time_scale=FAST)
    delivery = robot.submit_goal("(crate_at parcel lab)")
    robot.wait_for_event("START", "drive(dock, store)", timeout=60)
    robot.unset_fact("(road store hall0)")  # as dura state unset does
    robot.wait_for(delivery, "achieved", timeout=120)
    events = robot.events()
    replan = next(
        i
        for i, e in enumerate(events)
        if e.kind == "REPLAN" and "drive(store, hall0) ahead" in e.data["reason"]
    )
    drives = [i for i, e in enumerate(events) if e.kind == "END" and "drive(" in e.subject]
    assert replan < drives[0]  # replanned while the robot was still on its first drive
    assert "(road store hall0) changed" in events[replan].data["reason"]
    driven = [e.subject for e in events[replan:] if e.kind == "END"]
    assert "drive(store, hall0)" not in driven, driven
    assert "(crate_at parcel lab)" in robot.facts("crate_at")


def test_a_dry_run_shows_a_plan_for_the_open_goals_and_executes_nothing(
    dura_robot: Start,
) -> None:
    robot = dura_robot(USECASE)  # real time: the goal stays open while the dry run plans
    goal = robot.submit_goal("(picture_taken office)")
    robot.wait_for_event("START", "move_to", timeout=60)
    dry = run_dura("plan", "--dry-run", cwd=robot.folder)
    assert dry.returncode == 0, dry.stderr
    assert f"for goal {goal} (nothing executed)" in dry.stdout, dry.stdout
    assert "take_picture(office)" in dry.stdout
    robot.wait_for(goal, "achieved", timeout=60)
    assert len(robot.events("PLAN_STORED")) == 1  # the dry run stored and ran nothing
