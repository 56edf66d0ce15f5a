"""A recording replayed through a robot's monitoring: monitoring in the loop.

:func:`replay_bag` opens a recording (a ROS 2 bag or a ``dura record`` MCAP file),
routes its topics to the robot description's, and replays it through the robot's
observers, diagnosis and repair rules (:mod:`monitoring.replay`) with the recording's
time as the clock; it returns the :class:`monitoring.timeline.Timeline`, deterministic,
so that a test can pin what a recorded incident must be diagnosed as::

    def test_the_lidar_dropout_of_tuesday_is_diagnosed(dura_replay):
        timeline = dura_replay("bags/lidar_dropout", "robot.yaml")
        assert timeline.diagnosed() == [("lidar",)]
        assert [r.action for r in timeline.repairs()] == ["restart lidar"]
        assert timeline.undecodable == ()  # every message the observers read decoded

``dura replay`` runs the same :class:`BagReplay` (of :mod:`executive.bag_replay`).
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

from executive.bag_replay import BagReplay
from knowledge.description import RobotDescription
from monitoring.timeline import Timeline

__all__ = ["BagReplay", "replay_bag"]


def replay_bag(
    path: str | Path,
    robot: str | Path | RobotDescription,
    *,
    maps: Sequence[str] = (),
    begin: float | None = None,
    end: float | None = None,
    types: Sequence[str | Path] = (),
) -> Timeline:
    """Replay a recording through a robot's observers, diagnosis and repair rules and
    return the timeline (see the module docstring)."""
    description = robot if isinstance(robot, RobotDescription) else Path(robot)
    folders = [Path(p) for p in types]
    with BagReplay(
        Path(path), description, maps=maps, begin=begin, end=end, types=folders
    ) as replay:
        return replay.run()
