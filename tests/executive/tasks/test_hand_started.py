"""Components started by hand (``dura component start``) are supervised like those the
task executor starts: in the diagnosis model, their crashes are faults and they are
restarted, and a task that also used them does not stop them when it ends."""

from __future__ import annotations

import os
import signal
from collections.abc import Iterator
from pathlib import Path

import pytest

from executive.bus.api.monitoring import DIAGNOSIS_MODEL_READ
from executive.testing.harness import RobotProcess, robot_variant
from tests.conftest import ROOT, USECASE, wait_for

pytestmark = pytest.mark.slow


@pytest.fixture
def robot(tmp_path: Path) -> Iterator[RobotProcess]:
    os.environ.setdefault("PYTHONPATH", str(ROOT))
    changes = {"behaviors": {"move_to": {"params": {"duration": 1.0}}}}
    description = robot_variant(USECASE, tmp_path / "description", changes)
    with RobotProcess(description, tmp_path / "run") as running:
        yield running


def state_of(robot: RobotProcess, name: str) -> dict[str, object]:
    listed = robot.request("component/list")["components"]
    return next(c for c in listed if c["component"] == name)


def modelled(robot: RobotProcess) -> set[str]:
    reply = DIAGNOSIS_MODEL_READ.call(robot.bus)
    assert reply.ok and reply.model is not None, reply.error
    return {node["name"] for node in reply.model["nodes"]}


def test_a_hand_started_component_is_modelled_and_its_crash_is_a_fault_and_restarted(
    robot: RobotProcess,
) -> None:
    started = robot.request("component/start", {"name": "lidar"})
    assert started["state"] == "ready"
    assert wait_for(lambda: "lidar" in modelled(robot), 10)
    os.kill(int(started["pid"]), signal.SIGKILL)
    assert wait_for(lambda: robot.events("FAULT") != [], 10)
    assert robot.events("FAULT")[0].subject == "lidar"
    assert wait_for(lambda: state_of(robot, "lidar")["state"] == "ready", 20)
    assert state_of(robot, "lidar")["pid"] != started["pid"]
    # the model follows the restart on the monitoring service's side, a moment later
    assert wait_for(lambda: "lidar" in modelled(robot), 10)


def test_a_task_that_used_a_hand_started_component_leaves_it_running(
    robot: RobotProcess,
) -> None:
    started = robot.request("component/start", {"name": "lidar"})
    task = robot.request("task/start", {"task": "move_to", "goal": {"target": "lab"}})["id"]
    assert wait_for(lambda: robot.events("TASK_SUCCEEDED") != [], 60)
    assert robot.events("TASK_SUCCEEDED")[0].subject.startswith(f"task {task} ")
    assert wait_for(lambda: state_of(robot, "lidar_filter")["state"] == "stopped", 10)
    assert state_of(robot, "lidar")["state"] == "ready"
    assert state_of(robot, "lidar")["pid"] == started["pid"]
    assert "lidar" in modelled(robot)
    stopped = robot.request("component/stop", {"name": "lidar"})
    assert stopped["state"] == "stopped"
    assert wait_for(lambda: "lidar" not in modelled(robot), 10)
