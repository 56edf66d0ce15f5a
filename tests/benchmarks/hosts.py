"""Benchmark of failover across computers, beside the same failover on one computer.

    python -m tests.benchmarks.hosts [--runs N]

The use case's move_to task runs on lidar and lidar_filter; cam and cam_to_lidar are
the alternative (both with ``max_faults: 1``, so that a fault moves the task at once).
Each run kills what provides the scan and times, in milliseconds, until cam_to_lidar
delivers its first filtered scan:
- across hosts: lidar and lidar_filter run on host 'front', the alternative on host
  'back' (two ``dura host`` agents on this machine); the front agent is SIGKILLed, as a
  power cut would end it;
- on one host: everything runs on the executive's computer; the lidar and lidar_filter
  programs are SIGKILLed.
Between runs the task is stopped, the faults are reset and (across hosts) a new front
agent joins.
"""

from __future__ import annotations

import argparse
import os
import signal
import tempfile
import threading
import time
from collections.abc import Callable, Iterator
from contextlib import ExitStack, contextmanager
from pathlib import Path
from typing import Any

from executive.bus.keys import topic
from executive.bus.message import Message
from executive.testing.harness import RobotProcess, robot_variant
from executive.testing.hosts import HostProcess
from tests.benchmarks.runtime import percentiles
from tests.conftest import ROOT, USECASE, wait_for

KEPT = {"max_faults": 1}
ONE_HOST = {
    "rules": None,  # no repair rule restarts what the diagnosis names: failover only
    "integrity": None,
    "functionalities": {"lidar": KEPT, "lidar_filter": KEPT},
    "behaviors": {"move_to": {"params": {"duration": 600.0, "input_timeout": 2.0}}},
}
ACROSS = {
    **ONE_HOST,
    "functionalities": {
        "lidar": {**KEPT, "host": "front"},
        "lidar_filter": {**KEPT, "host": "front"},
        "cam": {"host": "back"},
        "cam_to_lidar": {"host": "back"},
        "robot_base": {"host": "back"},
    },
}


class Scans:
    """When each component last published the filtered scan (monotonic seconds)."""

    def __init__(self) -> None:
        self._seen: list[tuple[str, float]] = []
        self._changed = threading.Condition()

    def heard(self, message: Message) -> None:
        with self._changed:
            self._seen.append((message.caller_id, time.monotonic()))
            self._changed.notify_all()

    def first(self, component: str, after: float, timeout: float = 30.0) -> float:
        """The first filtered scan of ``component`` after ``after``."""
        deadline = time.monotonic() + timeout
        with self._changed:
            while True:
                found = [t for c, t in self._seen if c == component and t > after]
                if found:
                    return found[0]
                if time.monotonic() > deadline:
                    raise TimeoutError(f"no filtered scan of {component} in {timeout:g} s")
                self._changed.wait(0.2)


def task_of(robot: RobotProcess, task_id: str) -> dict[str, Any]:
    return next(t for t in robot.request("task/list")["tasks"] if t["id"] == task_id)


def failover(robot: RobotProcess, scans: Scans, kill: Callable[[], None]) -> float:
    """One failover from lidar_filter to cam_to_lidar, in seconds."""
    for name in ("lidar", "lidar_filter"):
        robot.request("component/reset", {"name": name})
    task_id = str(robot.request("task/start", {"task": "move_to",
                                               "goal": {"start": "dock", "target": "lab"}})["id"])  # fmt: skip
    assert wait_for(lambda: task_of(robot, task_id)["state"] == "running", 60), task_id
    assert "lidar_filter" in task_of(robot, task_id)["providers"].values()
    scans.first("lidar_filter", time.monotonic())  # data flows
    killed = time.monotonic()
    kill()
    delivered = scans.first("cam_to_lidar", killed)
    robot.request("task/stop", {"id": task_id})
    assert wait_for(lambda: task_of(robot, task_id)["state"] != "running", 60)
    assert wait_for(lambda: robot.component_state("cam_to_lidar") != "ready", 60)
    return delivered - killed


@contextmanager
def executive(folder: Path, changes: dict[str, Any]) -> Iterator[tuple[RobotProcess, Scans]]:
    description = robot_variant(USECASE, folder / "description", changes)
    with RobotProcess(description, folder) as robot:
        scans = Scans()
        robot.bus.subscribe(topic("scan_filtered"), scans.heard)
        yield robot, scans


def across_hosts(runs: int, folder: Path) -> list[float]:
    samples = []
    with executive(folder, ACROSS) as (robot, scans), ExitStack() as agents:
        description = robot.description

        def agent(name: str) -> HostProcess:
            host = HostProcess(description, folder, name, robot.endpoint, args=["--lease", "1"])
            return agents.enter_context(host)

        agent("back")
        for _ in range(runs):
            joined = len(robot.events("HOST_JOINED"))
            front = agent("front")  # a new agent: the last one was killed
            assert wait_for(lambda n=joined: len(robot.events("HOST_JOINED")) > n, 30)
            samples.append(failover(robot, scans, front.kill))
    return samples


def one_host(runs: int, folder: Path) -> list[float]:
    samples = []
    with executive(folder, ONE_HOST) as (robot, scans):

        def kill() -> None:
            listed = robot.request("component/list")["components"]
            for c in listed:
                if c["component"] in ("lidar", "lidar_filter") and c["pid"] is not None:
                    os.kill(int(c["pid"]), signal.SIGKILL)

        for _ in range(runs):
            samples.append(failover(robot, scans, kill))
    return samples


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=10, help="failovers of each kind")
    args = parser.parse_args()
    os.environ["PYTHONPATH"] = str(ROOT)
    with tempfile.TemporaryDirectory() as tmp:
        results = {
            "on one host (baseline)": one_host(args.runs, Path(tmp) / "one"),
            "across hosts": across_hosts(args.runs, Path(tmp) / "across"),
        }
    print("kill of what provides the scan -> first filtered scan of the alternative")
    print(f"{'failover':<24} {'n':>4} {'p50 ms':>8} {'p95 ms':>8}")
    for name, samples in results.items():
        p50, p95 = percentiles(samples)
        print(f"{name:<24} {len(samples):>4} {p50 * 1000:>8.1f} {p95 * 1000:>8.1f}")


if __name__ == "__main__":
    main()
