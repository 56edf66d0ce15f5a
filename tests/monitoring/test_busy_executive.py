"""A busy executive is not a silent publisher: the observer manager on a real bus, a
scripted publisher process that never stops, and an executive whose subscription
handler threads are held back for a while, as a loaded machine holds them (they wait
for the CPU or the interpreter while the observers' loop runs).

Measured before the fix, under CPU load at robot time x10: the timeout observer said
"no message for 0.585 s" while the lidar had sent a scan every 0.1 s and another
process had received each within 14 ms.
"""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import pytest

from executive.bus.payloads import GENERAL_OK
from executive.bus.session import Bus
from knowledge.description import RobotDescription
from tests.executive.bus.test_polled import HeldBus
from tests.monitoring.harness import (
    Observations,
    Publish,
    publish,
    robot,
    running_manager,
    seen,
    stream,
)
from tests.monitoring.observers.test_timeout import timeout_observer

__all__ = ["publish", "robot"]  # the fixtures this module uses

HELD = 1.5  # seconds the handler threads wait: three times the observers' timeout


@pytest.fixture
def busy(robot: RobotDescription) -> Iterator[HeldBus]:
    with HeldBus(robot.name, name="executive", endpoint=robot.endpoint, listen=True) as opened:
        yield opened


@pytest.fixture
def watched(robot: RobotDescription, busy: HeldBus) -> Iterator[Observations]:
    """The observations, as another process on the robot's bus sees them."""
    with Bus(robot.name, name="watcher", endpoint=robot.endpoint) as other:
        yield Observations(other)


def test_handler_threads_held_back_are_not_counted_as_the_publishers_silence(
    robot: RobotDescription,
    busy: HeldBus,
    watched: Observations,
    publish: Publish,
    tmp_path: Path,
) -> None:
    publish("lidar", [stream("topic/scan", {"rate": 20})])  # for ever
    frequency = {
        "type": "frequency",
        "topics": [{"name": "scan", "callerids": [{
            "callerid": [], "filter": {"type": "mean", "window_size": 10}, "timeout": 0.5,
            "states": [{"state": "ok", "number": 1, "frequency": {
                "type": "in_between", "lower_bound": 10.0, "upper_bound": 30.0}}],
        }]}],
    }  # fmt: skip
    with running_manager(robot, busy, tmp_path) as manager:
        manager.add({**timeout_observer(0.5), "main_loop_rate": 10.0})
        manager.add({**frequency, "main_loop_rate": 10.0})
        watched.next(seen("timeout", ["scan"], GENERAL_OK))
        watched.next(seen("frequency", ["scan"], 1))
        busy.free.clear()
        try:
            during = watched.during(HELD)
        finally:
            busy.free.set()
    assert {o["type"] for o in during} == {"timeout", "frequency"}
    failed = [o["verbose_observation_msg"] for o in during if o["observation_msg"] != "ok"]
    assert failed == []
