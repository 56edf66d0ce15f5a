"""Observers measure robot time: with a time scale, what they watch runs faster too."""

from __future__ import annotations

from pathlib import Path

from executive.bus.clock import Clock
from executive.bus.message import Message
from executive.bus.service import Context
from executive.bus.session import Bus
from knowledge.description import RobotDescription
from knowledge.knowledge_base import KnowledgeBase
from monitoring.observer_manager import ObserverManager
from monitoring.robot_time import RobotTime
from tests.monitoring.harness import (
    Observations,
    Publish,
    bus,
    observations,
    publish,
    robot,
    stream,
)
from tests.monitoring.test_observer_manager import frequency, of

__all__ = ["bus", "observations", "publish", "robot"]


def test_a_message_on_the_robot_time_axis_has_its_times_and_stamp_scaled() -> None:
    message = Message("topic/scan", b'{"stamp": 100.0, "ranges": [1]}', "lidar", 101.0, 102.0)
    seen = RobotTime(Clock(10.0)).message(message)
    assert (seen.sent, seen.received, seen.stamp) == (1010.0, 1020.0, 1000.0)
    assert seen.payload == {"stamp": 100.0, "ranges": [1]}
    assert (seen.key, seen.caller_id) == ("topic/scan", "lidar")
    assert RobotTime(Clock()).message(message) is message


def test_a_topic_ten_times_faster_on_the_wall_clock_is_at_its_rate_in_robot_time(
    tmp_path: Path,
    robot: RobotDescription,
    bus: Bus,
    observations: Observations,
    publish: Publish,
) -> None:
    publish("lidar", [stream("topic/scan", {"rate": 50})])  # 5 Hz of robot time
    with KnowledgeBase(tmp_path / "kb.db") as kb:
        manager = ObserverManager(Context(robot, bus, kb), clock=Clock(10.0))
        manager.configure()
        manager.activate()
        try:
            observer = manager.add(frequency(low=3.5, high=6.5), name="scan rate")
            found = observations.next(of(observer))
        finally:
            manager.shutdown()
    assert found["observation"] == 1, found
    assert 3.5 <= found["values"]["frequency"] <= 6.5
