"""What the observer tests share: a small robot, a running observer manager on a real bus,
scripted publisher processes, and a collector of the observations published.

Test modules import the fixtures they use from here.
"""

from __future__ import annotations

import contextlib
import json
import subprocess
import sys
import threading
import time
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import pytest

from executive.bus.keys import OBSERVATIONS, component
from executive.bus.message import Message
from executive.bus.payloads import ComponentState
from executive.bus.service import Context
from executive.bus.session import Bus
from executive.bus.states import Lifecycle
from knowledge.description import RobotDescription
from knowledge.knowledge_base import KnowledgeBase
from knowledge.robot import read_robot
from monitoring.observer_manager import ObserverManager
from tests.conftest import ROOT

DOMAIN = ROOT / "domains" / "usecase" / "domain.pddl"

ROBOT = """\
robot: monitored
domain: {domain}
bus: {{endpoint: {endpoint}}}
functionalities:
  lidar:
    command: [python, -c, pass]
    publishes: [scan]
    observers: {observers}
  other:
    command: [python, -c, pass]
    publishes: [scan]
  robot_base:
    command: [python, -c, pass]
    publishes: [odom, imu]
behaviors:
  move_to:
    command: [python, -c, pass]
    subscribes: [scan, odom, imu]
{extra}"""


def write_robot(folder: Path, endpoint: str, observers: str = "[]", extra: str = "") -> Path:
    """The test robot; ``observers`` (flow YAML) are lidar's, ``extra`` is appended."""
    path = folder / "robot.yaml"
    path.write_text(
        ROBOT.format(domain=DOMAIN, endpoint=endpoint, observers=observers, extra=extra)
    )
    return path


@pytest.fixture
def robot(tmp_path: Path, endpoint: str) -> RobotDescription:
    found, findings = read_robot(write_robot(tmp_path, endpoint))
    assert found is not None and not [f for f in findings if f.is_error], findings
    return found


@pytest.fixture
def bus(robot: RobotDescription) -> Iterator[Bus]:
    with Bus(robot.name, name="executive", endpoint=robot.endpoint, listen=True) as opened:
        yield opened


@contextlib.contextmanager
def running_manager(robot: RobotDescription, bus: Bus, folder: Path) -> Iterator[ObserverManager]:
    with KnowledgeBase(folder / "kb.db") as kb:
        started = ObserverManager(Context(robot, bus, kb))
        started.configure()
        started.activate()
        try:
            yield started
        finally:
            started.shutdown()


@pytest.fixture
def manager(robot: RobotDescription, bus: Bus, tmp_path: Path) -> Iterator[ObserverManager]:
    with running_manager(robot, bus, tmp_path) as started:
        yield started


class Observations:
    """Every observation published on the bus, in order, with a cursor for sequences."""

    def __init__(self, bus: Bus) -> None:
        self.items: list[dict[str, Any]] = []
        self._cursor = 0
        self._changed = threading.Condition()
        bus.subscribe(OBSERVATIONS, self._on)

    def _on(self, message: Message) -> None:
        with self._changed:
            self.items.append(message.payload)
            self._changed.notify_all()

    def next(
        self, predicate: Callable[[dict[str, Any]], bool], timeout: float = 15.0
    ) -> dict[str, Any]:
        """The first observation after the cursor that matches; moves the cursor past it."""
        deadline = time.monotonic() + timeout
        with self._changed:
            while True:
                for i in range(self._cursor, len(self.items)):
                    if predicate(self.items[i]):
                        self._cursor = i + 1
                        return self.items[i]
                left = deadline - time.monotonic()
                if left <= 0:
                    seen = [(o["type"], o["resource"], o["observation"]) for o in self.items[-10:]]
                    raise AssertionError(f"no such observation within {timeout} s; last: {seen}")
                self._changed.wait(left)

    def during(self, seconds: float) -> list[dict[str, Any]]:
        """The observations published from now on for a while."""
        with self._changed:
            start = len(self.items)
        time.sleep(seconds)
        with self._changed:
            self._cursor = len(self.items)
            return self.items[start:]


def seen(
    kind: str, resource: list[str], number: int | None = None, callerids: list[str] | None = None
) -> Callable[[dict[str, Any]], bool]:
    """A predicate: an observation of a type and resource (and number, and caller ids)."""

    def matches(o: dict[str, Any]) -> bool:
        return (
            o["type"] == kind
            and o["resource"] == resource
            and (number is None or o["observation"] == number)
            and (callerids is None or o["callerids"] == callerids)
        )

    return matches


@pytest.fixture
def observations(bus: Bus) -> Observations:
    return Observations(bus)


Publish = Callable[[str, list[dict[str, Any]]], subprocess.Popen[str]]


@pytest.fixture
def publish(robot: RobotDescription) -> Iterator[Publish]:
    """Start a scripted publisher process: publish(caller_id, streams)."""
    processes: list[subprocess.Popen[str]] = []

    def start(name: str, streams: list[dict[str, Any]]) -> subprocess.Popen[str]:
        process = subprocess.Popen(
            [
                sys.executable,
                "-m",
                "tests.monitoring.publisher",
                robot.name,
                robot.endpoint,
                name,
                json.dumps({"streams": streams}),
            ],
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            text=True,
            cwd=ROOT,
        )
        processes.append(process)
        assert process.stdout is not None
        assert process.stdout.readline().strip() == "ready"
        return process

    yield start
    for process in processes:
        stop_publisher(process)


def stop_publisher(process: subprocess.Popen[str]) -> None:
    """End a publisher: close its stdin, then kill it if it does not end."""
    if process.stdin is not None and not process.stdin.closed:
        process.stdin.close()
    try:
        process.wait(10)
    except subprocess.TimeoutExpired:
        process.kill()
        process.wait(10)
    if process.stdout is not None:
        process.stdout.close()


def set_state(bus: Bus, name: str, state: Lifecycle) -> None:
    """Report a component's lifecycle state, as the launcher does."""
    bus.publish(
        component(name, "state"), ComponentState(name, state, stamp=time.time()).to_payload()
    )


def wait_until(condition: Callable[[], bool], timeout: float = 15.0) -> None:
    deadline = time.monotonic() + timeout
    while not condition():
        if time.monotonic() > deadline:
            raise AssertionError(f"not so within {timeout} s")
        time.sleep(0.01)


def stream(key: str, *phases: dict[str, Any]) -> dict[str, Any]:
    return {"key": key, "phases": list(phases)}
