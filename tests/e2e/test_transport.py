"""The second example robot end to end: a transport robot that takes a lift between
floors and recharges at its docking station when its battery runs low (the integrity
goal). Real components, a real planner, the real executive."""

from __future__ import annotations

from collections.abc import Callable

import pytest

from executive.harness import RobotProcess
from tests.conftest import ROOT

pytestmark = pytest.mark.slow

TRANSPORT = ROOT / "examples" / "transport" / "robot.yaml"
Start = Callable[..., RobotProcess]


def steps(robot: RobotProcess) -> list[str]:
    """The actions that ended, in order: ``drive(dock, store)``, ..."""
    return [e["subject"] for e in robot.events("END")]


def test_a_crate_goes_upstairs_by_lift(dura_robot: Start) -> None:
    robot = dura_robot(TRANSPORT)
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
    # a battery that runs low on the way: the base says so, an integrity goal follows
    battery = {"battery": 24.0, "low": 20.0, "drain": 1.0}
    robot = dura_robot(TRANSPORT, changes={"functionalities": {"base": {"params": battery}}})
    delivery = robot.submit_goal("(crate_at parcel lab)")
    robot.wait_for(delivery, "achieved", timeout=240)
    recharge = [g for g in robot.goals() if g["source"] == "integrity"]
    assert [g["expression"] for g in recharge] == ["(and (not (battery_low)) (robot_at dock))"]
    robot.wait_for(recharge[0]["id"], "achieved", timeout=120)
    assert any(s.startswith("charge") for s in steps(robot))
    assert robot.facts("battery_low") == []
    assert "(crate_at parcel lab)" in robot.facts("crate_at")
