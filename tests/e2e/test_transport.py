"""The second example robot end to end: a transport robot that takes a lift between
floors and recharges at its docking station when its battery runs low (a sensing rule
sets the fact, an integrity goal follows). Real components, a real planner, the real
executive, with robot time ten times faster than the wall clock."""

from __future__ import annotations

from collections.abc import Callable

import pytest

from executive.testing.harness import RobotProcess
from tests.conftest import ROOT, wait_for

pytestmark = pytest.mark.slow

TRANSPORT = ROOT / "examples" / "transport" / "robot.yaml"
Start = Callable[..., RobotProcess]
FAST = 10.0  # robot time ten times faster: the same steps, in a tenth of their time


def steps(robot: RobotProcess) -> list[str]:
    """The actions that ended, in order: ``drive(dock, store)``, ..."""
    return [e.subject for e in robot.events("END")]


def started(robot: RobotProcess) -> list[str]:
    """The actions that started, in order."""
    return [e.subject for e in robot.events("START")]


def test_a_crate_goes_upstairs_by_lift(dura_robot: Start) -> None:
    robot = dura_robot(TRANSPORT, time_scale=FAST)
    goal = robot.submit_goal("(crate_at parcel lab)")
    robot.wait_for(goal, "achieved", timeout=180)
    assert "(crate_at parcel lab)" in robot.facts("crate_at")
    assert "(robot_at lab)" in robot.facts("robot_at")
    done = steps(robot)
    assert any(s.startswith("ride_lift") for s in done), done
    assert done.index(next(s for s in done if s.startswith("pick"))) < done.index(
        next(s for s in done if s.startswith("ride_lift"))
    )


def test_a_low_battery_sends_the_robot_to_charge_and_the_delivery_still_happens(
    dura_robot: Start,
) -> None:
    # a battery that runs low on the way: the sensing rule sets (battery_low), an
    # integrity goal follows
    battery = {"battery": 22.5, "drain": 1.0, "charge_rate": 40.0}
    changes = {"functionalities": {"base": {"params": battery}}}
    robot = dura_robot(TRANSPORT, changes=changes, time_scale=FAST)
    delivery = robot.submit_goal("(crate_at parcel lab)")
    robot.wait_for(delivery, "achieved", timeout=240)
    recharge = [g for g in robot.goals() if g.source == "integrity"]
    assert [g.expression for g in recharge] == ["(and (not (battery_low)) (robot_at dock))"]
    robot.wait_for(recharge[0].id, "achieved", timeout=120)
    # the robot charged: the step started; it ends, or is cancelled once the sensing rule
    # clears (battery_low) while it charges (its plan then serves no open goal)
    assert any(s.startswith("charge") for s in started(robot))
    assert robot.facts("battery_low") == []
    assert "(crate_at parcel lab)" in robot.facts("crate_at")


def test_a_lost_lift_makes_the_delivery_unreachable_and_sends_the_robot_to_its_dock(
    dura_robot: Start,
) -> None:
    robot = dura_robot(TRANSPORT, time_scale=FAST)
    delivery = robot.submit_goal("(crate_at parcel lab)")
    assert wait_for(lambda: any(s.startswith("pick") for s in started(robot)), timeout=60)
    robot.request("component/fault", {"name": "lift_link"})  # beyond repair
    goal = robot.wait_for(delivery, "unreachable", timeout=60)
    assert goal.reason.endswith(
        "; cannot run now: call_lift, ride_lift"
        " (no provider for capability 'lift': lift_link is permanently faulty)"
    ), goal.reason
    replans = [e.data["reason"] for e in robot.events("PLANNING")]
    assert any("call_lift, ride_lift can no longer run" in r for r in replans), replans
    maintenance = [g for g in robot.goals() if g.source == "integrity"]
    assert [g.expression for g in maintenance] == ["(robot_at dock)"]
    robot.wait_for(maintenance[0].id, "achieved", timeout=120)
    assert "(robot_at dock)" in robot.facts("robot_at")
    assert not any(s.startswith("ride_lift") for s in steps(robot))
