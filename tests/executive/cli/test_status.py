"""``dura status`` answers from snapshots: never behind a component that is starting."""

from __future__ import annotations

import json
from pathlib import Path

from executive.bus.api.components import COMPONENT_LIST
from executive.testing.harness import RobotProcess, robot_variant
from tests.conftest import USECASE, run_dura, wait_for

SLOW = 8.0  # seconds the camera takes to configure, as a driver waiting for its hardware


def test_status_answers_while_a_component_start_is_in_progress(tmp_path: Path) -> None:
    slow_camera = {
        "functionalities": {
            "cam": {
                "command": ["python", "-m", "tests.executive.tasks.slow_start"],
                "params": {"delay": SLOW, "rate": 15.0},
                "startup_timeout": SLOW + 10,
            }
        }
    }
    description = robot_variant(USECASE, tmp_path / "robot", slow_camera)
    with RobotProcess(description, tmp_path / "run") as robot:
        ask = ("--robot", str(description), "--endpoint", robot.endpoint)
        started = run_dura("task", "start", "take_picture", "--arg", "place=lab", *ask,
                           cwd=robot.folder)  # fmt: skip
        assert started.returncode == 0, started.stderr
        assert wait_for(lambda: _state(robot, "cam") == "starting", timeout=20)
        done = run_dura("status", "--json", *ask, cwd=robot.folder)
        assert done.returncode == 0, done.stderr
        status = json.loads(done.stdout)
        # the task executor is inside the camera's start: status answered without waiting
        assert _state(robot, "cam") == "starting"
        assert {c["component"]: c["state"] for c in status["components"]}["cam"] == "starting"
        assert [t["state"] for t in status["tasks"]] == ["starting"]


def _state(robot: RobotProcess, name: str) -> str:
    listed = COMPONENT_LIST.call(robot.bus).components
    return next(c.state.value for c in listed if c.component == name)
