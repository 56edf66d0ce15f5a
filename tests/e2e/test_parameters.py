"""Parameters at run time with the whole executive: a repair rule that fires on high CPU
lowers lidar's rate, lidar takes it while it runs, and its frequency observer sees the
new rate; ``dura param`` reads and changes parameters, and refuses a bad value."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import threading
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
import yaml

from executive.bus import security
from executive.bus.keys import OBSERVATIONS
from executive.bus.message import Message
from executive.testing.harness import RobotProcess, robot_variant
from tests.conftest import ROOT, USECASE, wait_for

pytestmark = pytest.mark.slow

FREQUENCY = {
    "type": "frequency",
    "main_loop_rate": 2.0,
    "start_up_time": 1.0,
    "topics": [{"name": "scan", "callerids": [{"callerid": [], "filter": {"type": "mean", "window_size": 10}, "states": [
        {"state": "ok", "number": 1, "frequency": {"type": "in_between", "lower_bound": 8.0, "upper_bound": 12.0}},
        {"state": "slow", "number": 2, "frequency": {"type": "in_between", "lower_bound": 3.0, "upper_bound": 7.0}},
    ]}]}],
}  # fmt: skip
RESOURCES = {
    "type": "resources",
    "main_loop_rate": 2.0,
    "nodes": [{"name": "lidar", "cpu_filter": {"type": "mean", "window_size": 2}, "states": [
        {"state": "normal", "number": 1, "cpu": {"type": "less_than", "less_than": 30.0}},
        {"state": "busy", "number": -1, "cpu": {"type": "greater_than", "greater_than": 30.0}},
    ]}]}  # fmt: skip
RULES = {
    "rules": [
        {
            "type": "parameter",
            "name": "slow_down_lidar",
            "component": "lidar",
            "key": "rate",
            "value": 5.0,
            "positive_observations": [{"type": "resources", "resource": "lidar"}],
            "single_shot": True,
        }
    ]
}


@pytest.fixture
def robot(tmp_path: Path) -> Iterator[RobotProcess]:
    os.environ.setdefault("PYTHONPATH", str(ROOT))
    changes = {
        "rules": ["cpu_rules.yaml"],
        "functionalities": {"lidar": {"observers": [FREQUENCY, RESOURCES]}},
    }
    description = robot_variant(USECASE, tmp_path / "description", changes)
    (description.parent / "cpu_rules.yaml").write_text(yaml.safe_dump(RULES))
    with RobotProcess(description, tmp_path / "run") as running:
        yield running


class Frequencies:
    """The frequencies lidar's frequency observer reports."""

    def __init__(self, robot: RobotProcess) -> None:
        self._lock = threading.Lock()
        self._seen: list[float] = []
        robot.bus.subscribe(OBSERVATIONS, self._add)

    def _add(self, message: Message) -> None:
        payload: dict[str, Any] = message.payload
        if payload.get("type") in ("frequency", "hz") and payload.get("resource") == ["scan"]:
            with self._lock:
                self._seen.append(float(payload.get("values", {}).get("frequency", 0.0)))

    def latest(self) -> float:
        with self._lock:
            return self._seen[-1] if self._seen else 0.0


def test_a_rule_on_high_cpu_lowers_lidars_rate_and_the_frequency_observer_sees_it(
    robot: RobotProcess,
) -> None:
    frequencies = Frequencies(robot)
    started = robot.request("component/start", {"name": "lidar"})
    assert wait_for(lambda: 8.0 <= frequencies.latest() <= 12.0, 30), frequencies.latest()
    robot.inject_fault("lidar", "high_cpu")
    assert wait_for(lambda: robot.events("PARAMETER") != [], 60)
    changed = robot.events("PARAMETER")[0]
    assert (changed.subject, changed.data) == ("lidar", {"key": "rate", "value": 5.0})
    assert any(e.subject == "slow_down_lidar" for e in robot.events("RULE_FIRED"))
    assert wait_for(lambda: 4.0 <= frequencies.latest() <= 6.0, 30), frequencies.latest()
    lidar = next(
        c for c in robot.request("component/list")["components"] if c["component"] == "lidar"
    )
    assert lidar["pid"] == started["pid"]  # it took the new rate while it ran


def test_dura_param_reads_changes_and_refuses_a_bad_value_in_one_line(
    robot: RobotProcess,
) -> None:
    credentials = security.credentials_file(robot.folder, robot.robot.name)
    env = {**os.environ, security.ENV_CREDENTIALS: str(credentials)}

    def dura(*args: str) -> subprocess.CompletedProcess[str]:
        argv = [sys.executable, "-m", "executive.cli", "param", *args]
        argv += ["--robot", str(robot.description), "--endpoint", robot.endpoint]
        return subprocess.run(argv, capture_output=True, text=True, timeout=60, env=env,
                              check=False)  # fmt: skip

    assert dura("get", "lidar", "rate").stdout == "10.0\n"
    changed = dura("set", "lidar", "rate", "4")
    assert changed.returncode == 0, changed.stderr
    assert changed.stdout == "lidar.rate = 4.0: it takes effect at the component's next start\n"
    refused = dura("set", "lidar", "rate", "fast")
    assert refused.returncode == 1
    assert refused.stderr == (
        "dura: parameter 'rate' of 'lidar' must be a number (the description gives 10.0), "
        "not 'fast'\n"
    )
    listed = json.loads(dura("list", "lidar", "--json").stdout)
    assert listed["parameters"] == {"rate": 4.0} and listed["sources"] == {"rate": "knowledge base"}
    unknown = dura("get", "lidar", "zoom")
    assert unknown.returncode == 1 and "'lidar' has no parameter 'zoom'" in unknown.stderr
