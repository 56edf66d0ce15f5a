"""A run recorded and replayed: a real ``dura run`` of the use case with a lidar fault,
recorded with ``dura record`` (and ``dura run --record``), replayed offline through the
same observers, diagnosis and rules gives what the live run diagnosed and repaired."""

from __future__ import annotations

import os
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest

from executive.bags.bag import Route
from executive.bags.reader import open_bag
from executive.bus.keys import OBSERVATIONS, observers_api
from executive.testing.harness import RobotProcess, robot_variant
from executive.testing.replay import replay_bag
from monitoring.timeline import Timeline
from tests.conftest import ROOT, USECASE, wait_for

pytestmark = pytest.mark.slow

LONG_MOVE = {"behaviors": {"move_to": {"params": {"duration": 30.0, "input_timeout": 3.0}}}}


def lidar_observed_ok(robot: RobotProcess) -> bool:
    latest = robot.bus.request(observers_api("latest"))["observations"]
    lidar = [o for o in latest if o["observer"].startswith("lidar/")]
    return len(lidar) == 2 and all(o["observation"] >= 0 for o in lidar)


def record(robot: RobotProcess, out: Path) -> subprocess.Popen[str]:
    """``dura record`` of a running robot, once it records."""
    argv = [sys.executable, "-m", "executive.cli", "record", str(out)]
    argv += ["--robot", str(robot.description), "--endpoint", robot.endpoint]
    process = subprocess.Popen(
        argv,
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
        env={**os.environ, "PYTHONPATH": str(ROOT)},
    )
    assert process.stdout is not None
    assert process.stdout.readline().startswith("dura: recording robot 'usecase'")
    return process


def test_a_recorded_run_replays_to_the_diagnoses_and_repairs_of_the_live_run(
    dura_robot: Callable[..., RobotProcess],
    dura_replay: Callable[..., Timeline],
    tmp_path: Path,
) -> None:
    robot = dura_robot(USECASE, changes=LONG_MOVE)
    out = tmp_path / "run.mcap"
    recorder = record(robot, out)
    try:
        robot.request("task/start", {"task": "move_to", "goal": {"start": "dock", "target": "lab"}})
        assert wait_for(lambda: lidar_observed_ok(robot), 30)
        robot.inject_fault("lidar", "stop_publishing")
        assert wait_for(lambda: robot.events("RULE_FIRED"), 20)
        assert wait_for(lambda: robot.events("TASK_RESTARTED"), 20)
        assert wait_for(lambda: lidar_observed_ok(robot), 30)  # restarted, publishing again
        live_repairs = [e["subject"] for e in robot.events("RULE_FIRED")]
    finally:
        robot.stop()
        recorder.wait(30)  # it ends with the executive
    assert recorder.returncode == 0
    timeline = dura_replay(out, robot.description)
    replayed, live = timeline.holds(), timeline.recorded_holds()
    assert [h.diagnosis for h in replayed] == [h.diagnosis for h in live] == [("lidar",)]
    for ours, theirs in zip(replayed, live, strict=True):
        assert ours.periods[0][0] == pytest.approx(theirs.periods[0][0], abs=0.2)
    assert [r.rule for r in timeline.repairs()] == live_repairs == ["restart_lidar"]
    states = [(s.component, s.state) for s in timeline.states()]
    assert ("lidar", "stopping") in states and states.count(("lidar", "ready")) == 2


def first_ok(observations: list[dict[str, Any]], observer: str) -> float:
    return min(o["stamp"] for o in observations if o["observer"] == observer)


def test_dura_run_records_its_own_traffic_and_its_observers_replay_as_they_ran(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setenv("PYTHONPATH", str(ROOT))
    description = robot_variant(USECASE, tmp_path / "description", {})
    out = tmp_path / "robot" / "run.mcap"
    robot = RobotProcess(description, tmp_path / "robot", run_args=["--record", str(out)])
    robot.start()
    try:
        robot.request("component/start", {"name": "lidar"})
        assert wait_for(lambda: lidar_observed_ok(robot), 30)
    finally:
        robot.stop()
    with open_bag(out) as bag:
        names = {t.name for t in bag.topics}
        assert {"topic/scan", "component/lidar/state", OBSERVATIONS, "resources"} <= names
        assert bag.robot == "usecase"
        observations = list(bag.messages({OBSERVATIONS: Route(OBSERVATIONS)}))
    live = [m.payload for m in observations]
    timeline = replay_bag(out, description)
    for observer in ("lidar/0", "lidar/1"):
        replayed = timeline.observations(observer)[0]
        assert replayed.info.observation_msg == "ok"
        assert timeline.origin + replayed.time == pytest.approx(first_ok(live, observer), abs=0.05)
