"""A robot on several computers: the use case with lidar and lidar_filter on host
'front', the camera, cam_to_lidar and the base on host 'back', and the behaviors on the
executive's computer. Real ``dura run`` and ``dura host`` processes on a real bus; where
the machine allows it, 'front' is another computer as far as the network goes: a
network namespace joined to this one by a veth pair, which the tests cut.
"""

from __future__ import annotations

import socket
import threading
import time
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import psutil
import pytest

from executive.bus.keys import DIAGNOSES, topic
from executive.bus.message import Message
from executive.testing.harness import RobotProcess, free_endpoint, robot_variant
from executive.testing.hosts import HostProcess, NetworkNamespace, namespaces_usable
from tests.conftest import USECASE, wait_for

pytestmark = pytest.mark.slow

PLACED = {
    "rules": None,  # the use case's rule restarts lidar when diagnosed: not here
    "integrity": None,
    "functionalities": {
        "lidar": {"host": "front"},
        "lidar_filter": {"host": "front"},
        "cam": {"host": "back"},
        "cam_to_lidar": {"host": "back"},
        "robot_base": {"host": "back"},
    },
    "behaviors": {"move_to": {"params": {"duration": 6.0, "input_timeout": 2.0}}},
}
NO_NAMESPACES = namespaces_usable()


def endpoint_on(address: str) -> str:
    with socket.socket() as s:
        s.bind((address, 0))
        return f"tcp/{address}:{s.getsockname()[1]}"


@dataclass
class Heard:
    """What a test hears on the bus: diagnoses, and when each component published the
    filtered scan."""

    diagnoses: list[dict[str, Any]] = field(default_factory=list)
    scans: list[tuple[str, float]] = field(default_factory=list)
    lock: threading.Lock = field(default_factory=threading.Lock)

    def on_diagnosis(self, message: Message) -> None:
        with self.lock:
            self.diagnoses.append(message.payload)

    def on_scan(self, message: Message) -> None:
        with self.lock:
            self.scans.append((message.caller_id, time.monotonic()))

    def named(self, component: str) -> bool:
        with self.lock:
            return any(
                d["status"] == "DIAGNOSED" and any(component in x for x in d["diagnoses"])
                for d in self.diagnoses
            )

    def first_scan(self, component: str, after: float) -> float | None:
        with self.lock:
            return next((t for c, t in self.scans if c == component and t > after), None)


@dataclass
class Rig:
    robot: RobotProcess
    front: HostProcess
    back: HostProcess
    heard: Heard
    network: NetworkNamespace | None


@pytest.fixture
def rig(tmp_path: Path) -> Iterator[Rig]:
    description = robot_variant(USECASE, tmp_path / "description", PLACED)
    with NetworkNamespace() if not NO_NAMESPACES else _nothing() as network:
        endpoint = endpoint_on(network.address) if network is not None else free_endpoint()
        with RobotProcess(description, tmp_path, endpoint) as robot:
            front_endpoint = endpoint
            heard = Heard()
            robot.bus.subscribe(DIAGNOSES, heard.on_diagnosis)
            robot.bus.subscribe(topic("scan_filtered"), heard.on_scan)
            namespace = network.name if network is not None else None
            args = ["--lease", "1"]
            with (
                HostProcess(description, tmp_path, "front", front_endpoint, namespace=namespace,
                            args=args) as front,
                HostProcess(description, tmp_path, "back", endpoint, args=args) as back,
            ):  # fmt: skip
                yield Rig(robot, front, back, heard, network)


class _nothing:
    def __enter__(self) -> None:
        return None

    def __exit__(self, *exc: object) -> None:
        return None


def start_move(robot: RobotProcess) -> str:
    reply = robot.request("task/start", {"task": "move_to", "goal": {"start": "dock",
                                                                      "target": "lab"}})  # fmt: skip
    return str(reply["id"])


def task(robot: RobotProcess, task_id: str) -> dict[str, Any]:
    return next(t for t in robot.request("task/list")["tasks"] if t["id"] == task_id)


def hosts_of(robot: RobotProcess) -> dict[str, str]:
    return {c["component"]: c["host"] for c in robot.request("component/list")["components"]}


def test_a_task_whose_configuration_spans_two_hosts_succeeds(rig: Rig) -> None:
    robot = rig.robot
    hosts = hosts_of(robot)
    assert (hosts["lidar"], hosts["robot_base"], hosts["cam"]) == ("front", "back", "back")
    task_id = start_move(robot)
    assert wait_for(lambda: task(robot, task_id)["state"] == "running", 60)
    uses = set(task(robot, task_id)["providers"].values())
    assert {"lidar", "lidar_filter", "robot_base"} <= uses
    front = {p.cmdline()[-1] for p in rig.front.programs()}
    back = {p.cmdline()[-1] for p in rig.back.programs()}
    assert front == {"components.lidar", "components.lidar_filter"}
    assert back == {"components.robot_base"}
    assert wait_for(lambda: task(robot, task_id)["state"] == "succeeded", 60), task(robot, task_id)
    logs = robot.request("component/logs", {"name": "lidar", "lines": 50})
    assert logs["path"].startswith("front:") and any("dura: started lidar" in line
                                                     for line in logs["lines"])  # fmt: skip


def test_a_killed_host_agent_is_no_fault_and_its_task_moves_to_the_other_host(rig: Rig) -> None:
    robot = rig.robot
    task_id = start_move(robot)
    assert wait_for(lambda: task(robot, task_id)["state"] == "running", 60)
    programs = rig.front.programs()
    assert len(programs) == 2
    killed = time.monotonic()
    rig.front.kill()
    # the supervisors end their trees once the agent is gone (the issue asks for 1 s:
    # measured and told, not asserted)
    assert wait_for(lambda: not any(running(p) for p in programs), 10), programs
    gone = time.monotonic() - killed
    assert wait_for(lambda: rig.heard.named("lidar_filter"), 30), rig.heard.diagnoses[-3:]
    assert wait_for(lambda: rig.heard.first_scan("cam_to_lidar", killed) is not None, 30)
    data = (rig.heard.first_scan("cam_to_lidar", killed) or killed) - killed
    print(
        f"host agent killed: its components gone after {gone:.3f} s, "
        f"the alternative on the other host delivered data after {data:.3f} s"
    )
    assert wait_for(lambda: task(robot, task_id)["state"] == "succeeded", 60), task(robot, task_id)
    assert set(task(robot, task_id)["providers"].values()) >= {"cam", "cam_to_lidar"}
    lost = robot.events("HOST_LOST")
    assert [e.subject for e in lost] == ["front"]
    assert set(lost[0].data["components"]) == {"lidar", "lidar_filter"}
    faults = {e.subject for e in robot.events("FAULT")}
    assert not faults & {"lidar", "lidar_filter"}  # unavailable, not faulty
    states = {c["component"]: c for c in robot.request("component/list")["components"]}
    assert states["lidar_filter"]["reason"] == "its host 'front' was lost"
    permanent = {c.name for c in robot.status().faults if c.permanent_fault}
    assert not permanent & {"lidar", "lidar_filter"}  # unavailable, not broken


@pytest.mark.skipif(bool(NO_NAMESPACES), reason=f"network namespaces: {NO_NAMESPACES}")
def test_a_partitioned_host_ends_its_components_and_rejoins_without_duplicates(
    rig: Rig,
) -> None:
    robot, front, network = rig.robot, rig.front, rig.network
    assert network is not None
    state = robot.request("component/start", {"name": "lidar"})
    assert state["state"] == "ready", state
    (program,) = front.programs()
    seen = len(front.lines)
    network.partition()
    front.wait_for_line("left (the executive was lost)", 30, after=seen)
    assert not running(program)
    assert wait_for(lambda: robot.component_state("lidar") == "exited", 30)
    (lost,) = robot.events("HOST_LOST")
    assert lost.subject == "front"
    refused = robot.request("component/start", {"name": "lidar"})
    assert refused["state"] == "failed" and "not connected" in refused["reason"]
    network.heal()
    front.wait_for_line("joined", 60, after=seen)
    assert wait_for(lambda: [e.subject for e in robot.events("HOST_JOINED")
                             if e.id > lost.id] == ["front"], 30)  # fmt: skip
    state = robot.request("component/start", {"name": "lidar"})
    assert state["state"] == "ready", state
    folder = robot.description.parent
    assert len(front.programs()) == 1 and len(programs_in(folder, "components.lidar")) == 1


def running(process: psutil.Process) -> bool:
    try:
        return process.is_running() and process.status() != psutil.STATUS_ZOMBIE
    except psutil.NoSuchProcess:
        return False


def programs_in(folder: Path, module: str) -> list[psutil.Process]:
    """The programs running ``python -m module`` in ``folder`` (this test's robot), not
    their supervisors (whose command lines end alike)."""
    found = []
    for process in psutil.process_iter(["cmdline"]):
        try:
            cmdline = process.info["cmdline"] or []  # a supervisor's: head -- program
            if cmdline[-1:] == [module] and "--" not in cmdline and Path(process.cwd()) == folder:
                found.append(process)
        except psutil.Error:
            continue
    return found


def test_a_lost_host_fires_no_repair_and_its_components_are_back_with_it(
    tmp_path: Path,
) -> None:
    # the use case's rule restarts lidar whenever the diagnosis names it, and its
    # integrity rule sends the robot home when a component is permanently faulty
    placed = {k: v for k, v in PLACED.items() if k not in ("rules", "integrity")}
    description = robot_variant(USECASE, tmp_path / "description", placed)
    with RobotProcess(description, tmp_path) as robot:
        args = ["--lease", "1"]
        with HostProcess(description, tmp_path, "front", robot.endpoint, args=args) as front:
            state = robot.request("component/start", {"name": "lidar"})
            assert state["state"] == "ready", state
            heard = Heard()
            robot.bus.subscribe(DIAGNOSES, heard.on_diagnosis)
            front.kill()
            robot.wait_for_event("HOST_LOST", "front", timeout=30)
            # lidar is not there: the diagnosis names it, and the rule would fire at once
            assert wait_for(lambda: heard.named("lidar"), 30), heard.diagnoses[-3:]
            time.sleep(2.0)  # nothing tells that a rule did not fire: give it the time
        fired = [e for e in robot.events("RULE_FIRED") if e.subject == "restart_lidar"]
        assert fired == [], fired
        assert [e.subject for e in robot.events("FAULT")] == []
        assert not any(c.permanent_fault for c in robot.status().faults)
        assert [g for g in robot.goals() if g.source == "integrity"] == []
        with HostProcess(description, tmp_path, "front", robot.endpoint, args=args):
            robot.wait_for_event("HOST_JOINED", "front", timeout=30)
            state = robot.request("component/start", {"name": "lidar"})
            assert state["state"] == "ready", state  # back without a reset


def test_a_stopped_host_agent_is_stopped_not_lost(tmp_path: Path) -> None:
    description = robot_variant(USECASE, tmp_path / "description", PLACED)
    with RobotProcess(description, tmp_path) as robot:
        with HostProcess(description, tmp_path, "front", robot.endpoint) as front:
            assert robot.request("component/start", {"name": "lidar"})["state"] == "ready"
            front.stop()  # as Ctrl-C does
            robot.wait_for_event("HOST_STOPPED", "front", timeout=30)
        assert robot.events("HOST_LOST") == []
        states = {c["component"]: c for c in robot.request("component/list")["components"]}
        assert states["lidar"]["reason"] == "its host 'front' was stopped"
