"""The use case's lidar stalled by its computer, not broken: a real ``dura run``, its real
lidar process stopped and continued (SIGSTOP, SIGCONT) as a loaded machine starves it.

A stall shorter than the lidar's stop bound leaves its rate loop behind its schedule;
the loop catches up the scans it missed, as a driver delivers what its sensor buffered,
so the frequency observer still sees 20 scans a second and nothing is diagnosed. A
stall longer than that bound is a lidar that stopped, and is diagnosed. Robot time
runs at the wall clock's pace, so that the stall is the one the test makes.
"""

from __future__ import annotations

import os
import signal
import threading
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from typing import Any

import pytest

from executive.bus.api.components import COMPONENT_START, ComponentName
from executive.bus.message import Message
from executive.testing.harness import RobotProcess
from tests.conftest import USECASE, wait_for

pytestmark = pytest.mark.slow

Start = Callable[..., RobotProcess]
STOP_BOUND = 2.0  # seconds without a scan that mean "stopped" (both observers)
RATE = 20.0  # scans a second: a window of 20 periods is a second

# lidar at 20 Hz; its frequency over the last 20 periods must be within 18..22 Hz
LIDAR = {
    "params": {"rate": RATE},
    "observers": [
        {
            "type": "frequency",
            "main_loop_rate": 2.0,
            "start_up_time": 2.0,
            "topics": [{"name": "scan", "callerids": [{
                "callerid": [],
                "filter": {"type": "mean", "window_size": 20},
                "timeout": STOP_BOUND,
                "states": [{"state": "ok", "number": 1, "frequency": {
                    "type": "in_between", "lower_bound": 18.0, "upper_bound": 22.0}}],
            }]}],
        },
        {
            "type": "timeout",
            "start_up_time": 2.0,
            "topics": [{"name": "scan", "callerids": [
                {"callerid": [], "timeout": STOP_BOUND, "max_timeouts_in_a_row": 2}]}],
        },
    ],
}  # fmt: skip


@contextmanager
def scan_observations(robot: RobotProcess) -> Iterator[list[dict[str, Any]]]:
    """Collect the observations of ``scan`` while in the block."""
    seen: list[dict[str, Any]] = []
    lock = threading.Lock()

    def on_observation(message: Message) -> None:
        if message.payload.get("resource") == ["scan"]:
            with lock:
                seen.append(message.payload)

    subscriber = robot.bus.subscribe("observations", on_observation)
    try:
        yield seen
    finally:
        subscriber.undeclare()


def running_lidar(dura_robot: Start) -> tuple[RobotProcess, int]:
    robot = dura_robot(USECASE, changes={"functionalities": {"lidar": LIDAR}}, time_scale=1.0)
    COMPONENT_START.call(robot.bus, ComponentName("lidar"))
    pid = robot.wait_for_component("lidar").pid
    assert pid is not None
    return robot, pid


def stall(pid: int, seconds: float) -> None:
    """Starve a process for ``seconds``, as a busy computer may."""
    os.kill(pid, signal.SIGSTOP)
    try:
        time.sleep(seconds)
    finally:
        os.kill(pid, signal.SIGCONT)


def frequencies(seen: list[dict[str, Any]]) -> list[dict[str, Any]]:
    return [o for o in list(seen) if o["type"] == "frequency"]


def test_a_lidar_stalled_shorter_than_its_stop_bound_catches_up_and_is_not_diagnosed(
    dura_robot: Start,
) -> None:
    robot, pid = running_lidar(dura_robot)
    with scan_observations(robot) as seen:
        # a full window of periods, all measured before the stall
        assert wait_for(lambda: len(frequencies(seen)) >= 4, 30)
        before = len(frequencies(seen))
        stall(pid, 0.35)  # 7 periods: within the loop's catch-up and the stop bound
        # until every period of the window came after the stall
        assert wait_for(lambda: len(frequencies(seen)) >= before + 5, 30)
    failed = [o["verbose_observation_msg"] for o in seen if o["observation_msg"] != "ok"]
    assert failed == []
    assert [e.subject for e in robot.events("FAULT")] == []


def test_a_lidar_stalled_longer_than_its_stop_bound_is_diagnosed(dura_robot: Start) -> None:
    robot, pid = running_lidar(dura_robot)
    with scan_observations(robot) as seen:
        assert wait_for(lambda: len(frequencies(seen)) >= 2, 30)
        stall(pid, STOP_BOUND + 1.0)
        fault = robot.wait_for_event("FAULT", "lidar", timeout=30)
    assert "the diagnosis names it" in fault.data["reason"]
    assert any(o["observation_msg"] in ("timeout", "stopped") for o in seen)
