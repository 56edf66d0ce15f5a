"""The resource monitor measures real processes and publishes on the real bus."""

from __future__ import annotations

import socket
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path

import psutil
import pytest

from executive.bus.keys import RESOURCES, component
from executive.bus.payloads import ComponentState, NodeInfo, ResourceInfo
from executive.bus.service import Context
from executive.bus.session import Bus
from executive.bus.states import Lifecycle
from knowledge.errors import ConfigError
from knowledge.knowledge_base import KnowledgeBase
from monitoring.resource_monitor import ResourceMonitor
from tests.executive.runtime.rig import USECASE_ROBOT, Recorder, Rig, rig, robot, usecase

# A parent that sleeps and a child that spins: a process tree of two.
SPINNER = (
    "import subprocess, sys, time; "
    "subprocess.Popen([sys.executable, '-c', 'while True: pass']); time.sleep(60)"
)


def nodes(recorder: Recorder) -> list[list[NodeInfo]]:
    return [list(ResourceInfo.from_payload(p).nodes) for p in recorder.payloads]


def node_seen(recorder: Recorder, check: object, timeout: float = 10.0) -> bool:
    return recorder.wait(
        lambda p: any(check(n) for n in ResourceInfo.from_payload(p).nodes),  # type: ignore[operator]
        timeout,
    )


@pytest.fixture
def watched(endpoint: str, tmp_path: Path) -> Iterator[tuple[Bus, Recorder]]:
    """A resource monitor at 10 Hz and a recorder of what it publishes."""
    with (
        Bus("usecase", name="executive", endpoint=endpoint, listen=True) as bus,
        KnowledgeBase(tmp_path / "kb.db") as kb,
    ):
        monitor = ResourceMonitor(Context(USECASE_ROBOT, bus, kb), rate=10.0)
        recorder = Recorder(bus, RESOURCES)
        monitor.configure()
        monitor.activate()
        try:
            yield bus, recorder
        finally:
            monitor.shutdown()


def announce(bus: Bus, name: str, pid: int, state: Lifecycle = Lifecycle.READY) -> None:
    bus.publish(component(name, "state"), ComponentState(name, state, pid).to_payload())


def test_the_cpu_and_memory_of_a_components_process_tree_are_reported(
    watched: tuple[Bus, Recorder],
) -> None:
    bus, recorder = watched
    spinner = subprocess.Popen([sys.executable, "-c", SPINNER])
    try:
        announce(bus, "spinner", spinner.pid)
        assert node_seen(recorder, lambda n: n.name == "spinner" and n.cpu > 50)
        info = ResourceInfo.from_payload(recorder.payloads[-1])
        assert info.hostname == socket.gethostname() and info.stamp > 0
        node = next(n for n in info.nodes if n.name == "spinner")
        assert node.pid == spinner.pid and node.memory > 10 * (1 << 20) and node.error == ""
    finally:
        for child in psutil.Process(spinner.pid).children():
            child.kill()
        spinner.kill()
        spinner.wait()


def test_a_vanished_process_is_reported_with_an_error(watched: tuple[Bus, Recorder]) -> None:
    bus, recorder = watched
    ended = subprocess.Popen([sys.executable, "-c", "pass"])
    ended.wait()
    announce(bus, "ghost", ended.pid)
    assert node_seen(recorder, lambda n: n.error == f"process {ended.pid} vanished")


def test_a_component_that_stopped_is_no_longer_reported(watched: tuple[Bus, Recorder]) -> None:
    bus, recorder = watched
    sleeper = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(60)"])
    try:
        announce(bus, "sleeper", sleeper.pid)
        assert node_seen(recorder, lambda n: n.name == "sleeper")
        announce(bus, "sleeper", sleeper.pid, Lifecycle.STOPPED)
        recorder.clear()
        assert recorder.wait(lambda p: True)
        assert all(n == [] for n in nodes(recorder))
    finally:
        sleeper.kill()
        sleeper.wait()


def test_a_rate_that_is_not_positive_is_refused(tmp_path: Path, endpoint: str) -> None:
    with (
        Bus("usecase", endpoint=endpoint, listen=True) as bus,
        KnowledgeBase(tmp_path / "kb.db") as kb,
        pytest.raises(ConfigError, match="rate must be positive, not 0"),
    ):
        ResourceMonitor(Context(USECASE_ROBOT, bus, kb), rate=0)


def monitored(r: Rig) -> ResourceMonitor:
    monitor = ResourceMonitor(Context(r.robot, r.bus, r.kb), rate=5.0)
    monitor.configure()
    monitor.activate()
    return monitor


def test_high_cpu_and_growing_memory_faults_show_in_the_resources(
    endpoint: str, tmp_path: Path
) -> None:
    with rig(robot(usecase("lidar"), usecase("cam")), endpoint, tmp_path) as r:
        recorder = Recorder(r.bus, RESOURCES)
        monitor = monitored(r)
        try:
            r.launcher.start("lidar")
            r.launcher.start("cam")
            assert node_seen(recorder, lambda n: n.name == "cam" and n.memory > 0)
            baseline = next(n for n in nodes(recorder)[-1] if n.name == "cam").memory
            r.launcher.inject_fault("lidar", "high_cpu")
            r.launcher.inject_fault("cam", {"mode": "growing_memory", "mb_per_s": 50})
            assert node_seen(recorder, lambda n: n.name == "lidar" and n.cpu > 50)
            assert node_seen(
                recorder, lambda n: n.name == "cam" and n.memory > baseline + (40 << 20)
            )
        finally:
            monitor.shutdown()
