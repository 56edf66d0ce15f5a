"""Whole process trees end with the executive: grandchildren of a component included,
when the executive is SIGKILLed, and what a killed predecessor left is ended by the next
executive on the same knowledge base, which is also the only one on it."""

from __future__ import annotations

import contextlib
import os
import signal
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path

import psutil
import pytest

from executive.testing.harness import RobotProcess, robot_variant
from tests.conftest import ROOT, USECASE, wait_for

pytestmark = pytest.mark.slow

# a program that leaves two grandchildren of the component: the shell and its sleeps
SLEEPERS = ["bash", "-c", "sleep 600 & sleep 600"]


def sleeper_robot(folder: Path) -> Path:
    """The use case with a translated program that forks: ``sleeper``."""
    command = ["python", "-m", "executive.runtime.translator", "process", "--", *SLEEPERS]
    return robot_variant(
        USECASE, folder / "description", {"functionalities": {"sleeper": {"command": command}}}
    )


def sleeps_of(pid: int) -> list[psutil.Process]:
    """The ``sleep 600`` processes below ``pid``."""
    return [
        p
        for p in psutil.Process(pid).children(recursive=True)
        if p.name() == "sleep" and p.cmdline()[1:] == ["600"]
    ]


def gone(process: psutil.Process) -> bool:
    """It ended (a zombie that init has not reaped yet has ended)."""
    try:
        return process.status() == psutil.STATUS_ZOMBIE
    except psutil.NoSuchProcess:
        return True


@contextlib.contextmanager
def robot_in(folder: Path) -> Iterator[RobotProcess]:
    robot = RobotProcess(sleeper_robot(folder), folder / "run")
    os.environ.setdefault("PYTHONPATH", str(ROOT))
    try:
        robot.start()
        yield robot
    finally:
        robot.stop()


def start_sleeper(robot: RobotProcess) -> tuple[int, list[psutil.Process]]:
    """Start the sleeper by hand; its pid and its two sleeps."""
    state = robot.request("component/start", {"name": "sleeper"})
    assert state["state"] == "ready", state
    pid = int(state["pid"])
    assert wait_for(lambda: len(sleeps_of(pid)) == 2, 10)
    return pid, sleeps_of(pid)


def test_sigkill_of_the_executive_ends_the_grandchildren_of_its_components(
    tmp_path: Path,
) -> None:
    with robot_in(tmp_path) as robot:
        pid, sleeps = start_sleeper(robot)
        tree = [psutil.Process(pid), *psutil.Process(pid).children(recursive=True)]
        robot.kill()
        assert wait_for(lambda: all(gone(p) for p in tree), 10), [p for p in tree if not gone(p)]
        assert all(gone(s) for s in sleeps)


def test_an_executive_ends_what_its_killed_predecessor_left(tmp_path: Path) -> None:
    with robot_in(tmp_path) as robot:
        start_sleeper(robot)
        executive = psutil.Process(robot._process.pid if robot._process else 0)
        # the executive is frozen first: it ends a component's group as soon as it sees its
        # supervisor die (and, on a busy machine, may have restarted the sleeper: its
        # tree is taken now)
        executive.send_signal(signal.SIGSTOP)
        tree = executive.children(recursive=True)
        sleeps = sleeps_of(executive.pid)
        dura = [p for p in [executive, *tree] if p not in sleeps]
        # the supervisors die first, then the executive and what they held: as if the
        # supervision failed, only the program's children are left
        dura.sort(key=lambda p: "supervisor.py" not in " ".join(p.cmdline()))
        for process in dura:
            with contextlib.suppress(psutil.NoSuchProcess):
                process.send_signal(signal.SIGKILL)
        robot.kill()
        left = [s for s in sleeps if not gone(s)]  # orphans under init
        assert left, f"no orphan to end: {sleeps}"
        robot.start()
        assert wait_for(lambda: all(gone(s) for s in left), 10)


def test_a_second_executive_on_one_knowledge_base_refuses_to_start(tmp_path: Path) -> None:
    with robot_in(tmp_path) as robot:
        pid = robot._process.pid if robot._process else 0
        done = subprocess.run(
            [sys.executable, "-m", "executive.cli", "run", str(robot.description),
             "--db", str(robot.kb_path), "--endpoint", "tcp/127.0.0.1:0"],
            cwd=tmp_path, capture_output=True, text=True, timeout=60, check=False,
            env={**os.environ, "PYTHONPATH": str(ROOT)},
        )  # fmt: skip
        assert done.returncode == 1, done.stderr
        lines = done.stderr.strip().splitlines()
        assert len(lines) == 1 and f"pid {pid}" in lines[0], done.stderr
        assert robot.status()  # the first one runs on
