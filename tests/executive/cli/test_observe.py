"""``dura observe``: the observations of a running robot, as a table, JSON, or a live feed."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path
from subprocess import CompletedProcess

from monitoring.observer_manager import ObserverManager
from tests.conftest import ROOT
from tests.monitoring.harness import (
    Observations,
    Publish,
    bus,
    manager,
    observations,
    publish,
    robot,
    seen,
    stream,
    write_robot,
)

__all__ = ["bus", "manager", "observations", "publish", "robot"]

Dura = Callable[..., CompletedProcess[str]]

FREQUENCY = {
    "type": "frequency",
    "main_loop_rate": 5.0,
    "topics": [
        {
            "name": "scan",
            "callerids": [
                {
                    "callerid": ["lidar"],
                    "filter": {"type": "mean", "window_size": 5},
                    "states": [
                        {
                            "state": "ok",
                            "number": 1,
                            "frequency": {"type": "greater_than", "greater_than": 10},
                        }
                    ],
                }
            ],
        }
    ],
}


def test_without_an_executive_observe_says_so_in_one_line(
    dura: Dura, tmp_path: Path, endpoint: str
) -> None:
    path = write_robot(tmp_path, endpoint)
    result = dura("observe", "--robot", str(path), timeout=60)
    assert result.returncode == 1
    assert result.stderr.startswith(f"dura: no executive for robot 'monitored' at {endpoint}")
    assert len(result.stderr.splitlines()) == 1


def test_observe_needs_to_know_which_robot(dura: Dura, tmp_path: Path) -> None:
    result = dura("observe", cwd=tmp_path)
    assert result.returncode == 1
    assert result.stderr.startswith(
        "dura: no executive runs in this folder (no .dura/executive.json)"
    )
    assert len(result.stderr.splitlines()) == 1


def test_observe_shows_the_latest_observation_of_every_resource(
    dura: Dura,
    tmp_path: Path,
    manager: ObserverManager,
    observations: Observations,
    publish: Publish,
) -> None:
    publish("lidar", [stream("topic/scan", {"rate": 20})])
    manager.add(FREQUENCY)
    manager.add({"type": "timeout", "topics": [{"name": "scan", "timeout": 1.0}]})
    observations.next(seen("frequency", ["scan"], 1))
    observations.next(seen("timeout", ["scan"]))
    result = dura("observe", "--robot", str(tmp_path / "robot.yaml"), timeout=60)
    assert result.returncode == 0, result.stderr
    header, *rows = result.stdout.splitlines()
    assert header.split() == ["RESOURCE", "TYPE", "STATE", "VALUE", "AGE"]
    assert rows[0].split()[:5] == ["scan", "[lidar]", "frequency", "ok", "(1)"]
    assert rows[1].split()[:4] == ["scan", "timeout", "ok", "(0)"]
    shown = json.loads(dura("observe", "--json", "--robot", str(tmp_path / "robot.yaml")).stdout)
    found = {o["type"]: o for o in shown["observations"]}
    assert found["frequency"]["values"]["frequency"] > 10
    assert found["frequency"]["callerids"] == ["lidar"] and found["frequency"]["age"] >= 0


def test_observe_follow_json_prints_each_observation_as_it_comes(
    tmp_path: Path, manager: ObserverManager, publish: Publish
) -> None:
    publish("lidar", [stream("topic/scan", {"rate": 20})])
    manager.add(FREQUENCY)
    process = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "executive.cli",
            "observe",
            "--follow",
            "--json",
            "--robot",
            str(tmp_path / "robot.yaml"),
        ],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        cwd=ROOT,
        env={**os.environ, "PYTHONPATH": str(ROOT)},
    )
    try:
        assert process.stdout is not None
        lines = [json.loads(process.stdout.readline()) for _ in range(3)]
        assert {(o["type"], tuple(o["resource"])) for o in lines} == {("frequency", ("scan",))}
        process.send_signal(signal.SIGINT)
        assert process.wait(30) == 0
    finally:
        if process.poll() is None:
            process.kill()
            process.wait(10)
        for stream_ in (process.stdout, process.stderr):
            if stream_ is not None:
                stream_.close()
