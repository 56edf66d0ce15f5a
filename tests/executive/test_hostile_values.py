"""Hostile values through the bus, as an operator's script could send them: parameter
keys that break the name rule, deadlines beyond what the command line allows, and inputs
so long that an error quoting them whole would be megabytes. Each is refused with a
short reason; nothing is stored; the executive keeps going."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import pytest

from executive.bus.api import parameters, planning
from executive.testing.harness import RobotProcess
from knowledge.errors import BusError
from tests.conftest import USECASE, run_dura


@pytest.fixture(scope="module")
def robot(tmp_path_factory: pytest.TempPathFactory) -> Iterator[RobotProcess]:
    with RobotProcess(USECASE, tmp_path_factory.mktemp("values")) as robot:
        yield robot


@pytest.mark.parametrize("key", ["../../k", "k\x00ey", "k" * 900_000, "", "a b", "é"])
def test_a_parameter_key_follows_the_name_rule(robot: RobotProcess, key: str) -> None:
    change = {"component": "lidar", "key": key, "value": 1}
    with pytest.raises(BusError) as refused:
        robot.bus.request(parameters.PARAMETER_SET.key, change, timeout=30)
    assert len(str(refused.value)) < 1000
    listed = parameters.PARAMETER_LIST.call(robot.bus, parameters.ComponentParameters("lidar"))
    assert set(listed.parameters) == set(robot.robot.components["lidar"].params)


@pytest.mark.parametrize("deadline", [1e308, 1e10, 0.0, -5.0])
def test_a_deadline_is_bounded_on_the_bus_as_on_the_command_line(
    robot: RobotProcess, deadline: float
) -> None:
    with pytest.raises(BusError, match="'deadline' must be"):
        request = {"expression": "(robot_at dock)", "deadline": deadline}
        robot.bus.request(planning.GOAL_ADD.key, request, timeout=30)
    assert robot.goals() == []


def test_an_error_reply_quotes_little_of_a_huge_request(robot: RobotProcess) -> None:
    expression = "(robot_at " + "x" * 900_000 + ")"
    with pytest.raises(BusError) as refused:
        robot.bus.request(planning.GOAL_ADD.key, {"expression": expression}, timeout=30)
    assert len(str(refused.value)) <= 500
    assert robot.goals() == []


def test_the_command_line_still_lists_the_parameters(robot: RobotProcess, tmp_path: Path) -> None:
    done = run_dura("param", "list", "lidar", "--json", cwd=robot.folder, env=robot.environment())
    assert done.returncode == 0, done.stderr
    assert robot.running
