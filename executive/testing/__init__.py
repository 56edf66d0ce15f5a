"""The pytest plugin for testing a robot with its planner in the loop (entry point
``pytest11``; active wherever dura is installed).

The ``dura_robot`` fixture starts the executive of a robot description in a temporary
folder and returns an :class:`executive.testing.harness.RobotProcess`: submit goals, wait for
them, inject faults, read events and facts (:class:`executive.testing.client.RobotClient`:
the goals, events, components and status come as typed records). Every robot it started
is stopped at the end of the test, with all its components::

    def test_pictures(dura_robot):
        robot = dura_robot("robot.yaml")
        goal = robot.submit_goal("(picture_taken lab)")
        assert robot.wait_for(goal, "achieved", timeout=60).state.value == "achieved"
        assert "(picture_taken lab)" in robot.facts("picture_taken")

Its sibling ``dura_replay`` puts monitoring in the loop: it replays a recording (a ROS 2
bag, or a run recorded with ``dura record``) through a robot's observers, diagnosis and
repair rules, with the recording's time as the clock, and returns the timeline
(:func:`executive.testing.replay.replay_bag`)::

    def test_the_lidar_dropout_is_diagnosed(dura_replay):
        timeline = dura_replay("bags/lidar_dropout", "robot.yaml")
        assert timeline.diagnosed() == [("lidar",)]

- :mod:`.harness` — a robot run by a real ``dura run`` process, driven over the bus
  (:class:`~.harness.RobotProcess`, and :class:`~.harness.ServiceGroupProcess` for a
  service group in a process of its own);
- :mod:`.fleet` — a fleet's high level run by a real ``dura fleet run`` process
  (:class:`~.fleet.FleetProcess`), beside its robots' :class:`~.harness.RobotProcess`;
- :mod:`.client` — what a test asks a running robot over the bus, answered with records
  (:class:`~.client.RobotClient`, the base of :class:`~.harness.RobotProcess`);
- :mod:`.replay` — a recording replayed through a robot's monitoring;
- :mod:`.hosts` — host agents as child processes, and network namespaces to put them
  in.

It may import :mod:`executive.bus`, :mod:`executive.sdk`, :mod:`executive.bags`,
:mod:`monitoring` and :mod:`knowledge`.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator, Mapping
from pathlib import Path
from typing import TYPE_CHECKING, Any

import pytest

from executive.testing.client import GoalEnded, RobotClient, WaitTimedOut
from executive.testing.fleet import FleetProcess, fleet_variant
from executive.testing.harness import RobotProcess, ServiceGroupProcess, robot_variant

if TYPE_CHECKING:
    from monitoring.timeline import Timeline

__all__ = [
    "FleetProcess",
    "GoalEnded",
    "RobotClient",
    "RobotProcess",
    "ServiceGroupProcess",
    "WaitTimedOut",
    "dura_replay",
    "dura_robot",
    "fleet_variant",
]


@pytest.fixture
def dura_robot(tmp_path: Path) -> Iterator[Callable[..., RobotProcess]]:
    """Start robots: ``dura_robot(description, name="robot", changes=None,
    time_scale=None, endpoint=None)`` → a running RobotProcess. ``changes`` modify a copy
    of the description, nested like its YAML (``{"behaviors": {"move_to": {"max_restarts":
    0}}}``); ``time_scale=10`` runs robot time ten times faster than the wall clock
    (default: ``DURA_TIME_SCALE`` of the test's environment, else 1); ``endpoint`` is
    where the executive listens (default: a free loopback port)."""
    started: list[RobotProcess] = []

    def start(
        description: str | Path,
        name: str = "robot",
        changes: Mapping[str, Any] | None = None,
        time_scale: float | None = None,
        endpoint: str | None = None,
    ) -> RobotProcess:
        folder = tmp_path / name
        if changes:
            description = robot_variant(Path(description), folder / "description", changes)
        robot = RobotProcess(Path(description), folder, endpoint, time_scale=time_scale)
        started.append(robot)
        robot.start()
        return robot

    yield start
    for robot in reversed(started):
        robot.stop()


@pytest.fixture
def dura_replay() -> Callable[..., Timeline]:
    """Replay recordings: ``dura_replay(bag, robot, maps=(), begin=None, end=None,
    types=())`` → the :class:`monitoring.timeline.Timeline` of the robot's monitoring over
    the recording (``types``: folders of message definitions the bag does not have)."""
    from executive.testing.replay import replay_bag  # monitoring and bag readers: only when used

    return replay_bag
