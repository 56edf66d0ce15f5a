"""The fleet's runner sends each step to the robot it names, and fails at once a step for
a robot that cannot act (the planner plans again without it)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from executive.fleet.availability import Availability
from executive.fleet.fleet_tasks import FleetTasks
from executive.fleet.robot_link import RobotLink
from executive.planning.partial_order import Step
from executive.planning.task_runner import Progress, StepReport
from knowledge.robot import load_robot
from tests.conftest import ROOT

EXAMPLE = ROOT / "examples" / "fleet"


def runner(availability: Availability) -> FleetTasks:
    links = {
        name: RobotLink(load_robot(EXAMPLE / f"{name}.yaml"), "tcp/127.0.0.1:1",
                        Path("nowhere.json"), "depot", on_alive=lambda robot, there: None)
        for name in ("r1", "r2")
    }  # fmt: skip
    return FleetTasks({"drive": 0, "pick": 0}, {"r1": "r1", "r2": "r2"}, links, availability)


def reports() -> tuple[StepReport, list[tuple[Progress, Any]]]:
    told: list[tuple[Progress, Any]] = []
    return StepReport(lambda _, progress, value: told.append((progress, value))), told


def test_a_step_names_its_robot_by_its_robot_parameter() -> None:
    tasks = runner(Availability({"r1": "r1", "r2": "r2"}, 3))
    assert tasks.performer("drive", ("r2", "dock2", "store")) == "r2"
    assert tasks.performer("pick", ("r9", "parcel1", "store")) is None  # no robot of it
    assert tasks.performer("wait", ("r1",)) is None  # an action no robot carries out


def test_a_step_for_a_robot_that_cannot_act_fails_at_once_with_the_reason() -> None:
    availability = Availability({"r1": "r1", "r2": "r2"}, 3)
    tasks = runner(availability)
    report, told = reports()
    tasks.run(Step(0, "drive", ("r1", "dock1", "store"), ("r", "from", "to"), 0.0, 5.0), 1, report)
    assert told == [
        (Progress.FAILED, "robot 'r1' is unavailable: its executive has not been seen yet")
    ]
    availability.joined("r1")  # there, but the fleet has no session with it yet
    report, told = reports()
    tasks.run(Step(1, "drive", ("r1", "dock1", "store"), ("r", "from", "to"), 0.0, 5.0), 1, report)
    assert told == [
        (Progress.FAILED, "robot 'r1' is unavailable: the fleet has not reached its executive")
    ]
    report, told = reports()
    tasks.run(Step(2, "wait", ("r1",), ("r",), 0.0, 1.0), 1, report)
    assert told == [(Progress.FAILED, "step wait(r1) names no robot of the fleet")]
