"""The pytest plugin for testing a robot with its planner in the loop (entry point
``pytest11``; active wherever dura is installed).

The ``dura_robot`` fixture starts the executive of a robot description in a temporary
folder and returns an :class:`executive.testing.harness.RobotProcess`: submit goals, wait for
them, inject faults, read events and facts. Every robot it started is stopped at the
end of the test, with all its components::

    def test_pictures(dura_robot):
        robot = dura_robot("robot.yaml")
        goal = robot.submit_goal("(picture_taken lab)")
        robot.wait_for(goal, "achieved", timeout=60)
        assert "(picture_taken lab)" in robot.facts("picture_taken")
"""

from __future__ import annotations

from collections.abc import Callable, Iterator, Mapping
from pathlib import Path
from typing import Any

import pytest

from executive.testing.harness import GoalEnded, RobotProcess, robot_variant

__all__ = ["GoalEnded", "RobotProcess", "dura_robot"]


@pytest.fixture
def dura_robot(tmp_path: Path) -> Iterator[Callable[..., RobotProcess]]:
    """Start robots: ``dura_robot(description, name="robot", changes=None, endpoint=None)``
    → a running RobotProcess. ``changes`` modify a copy of the description, nested like its
    YAML (``{"behaviors": {"move_to": {"max_restarts": 0}}}``); ``endpoint`` is where the
    executive listens (default: a free loopback port)."""
    started: list[RobotProcess] = []

    def start(
        description: str | Path,
        name: str = "robot",
        changes: Mapping[str, Any] | None = None,
        endpoint: str | None = None,
    ) -> RobotProcess:
        folder = tmp_path / name
        if changes:
            description = robot_variant(Path(description), folder / "description", changes)
        robot = RobotProcess(Path(description), folder, endpoint)
        started.append(robot)
        robot.start()
        return robot

    yield start
    for robot in reversed(started):
        robot.stop()
