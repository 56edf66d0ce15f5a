"""``dura run`` shows what the robot does: with ``--log`` (or on a terminal) a line for
each plan, step, component and goal in the demo's timeline format; in a pipe without it,
nothing but its first and last line."""

from __future__ import annotations

import os
import pty
import re
import signal
import subprocess
import sys
from pathlib import Path

import pytest

from tests.conftest import ROOT, free_endpoint, run_dura

pytestmark = pytest.mark.slow

LINE = re.compile(r" +\d+\.\ds  [A-Z_]+ +\S.*")  # the timeline's: time, kind, text
TABLE_ROW = re.compile(r" {9}\S.*")  # a plan's steps, under the time column


def run_robot(folder: Path, *flags: str) -> list[str]:
    """Run the robot of ``folder`` until its goal is achieved; what ``dura run`` printed."""
    endpoint = free_endpoint()
    env = {**os.environ, "PYTHONPATH": str(ROOT), "DURA_TIME_SCALE": "10"}
    argv = [sys.executable, "-m", "executive.cli", "run", "robot.yaml", "--endpoint", endpoint]
    with subprocess.Popen(
        [*argv, *flags], cwd=folder, env=env, stdout=subprocess.PIPE, text=True
    ) as process:
        assert process.stdout is not None
        try:
            first = process.stdout.readline()
            assert first.startswith("dura: executive of robot 'rover' runs on"), first
            added = run_dura("goal", "add", "(inspected kitchen)", "--wait", cwd=folder, env=env)
            assert added.returncode == 0, added.stdout + added.stderr
        finally:
            process.send_signal(signal.SIGINT)
        rest, _ = process.communicate(timeout=60)
    return [first.rstrip("\n"), *rest.splitlines()]


def test_dura_run_logs_plans_steps_and_goals_in_the_timeline_format_and_is_quiet_in_a_pipe(
    tmp_path: Path,
) -> None:
    assert run_dura("new", "rover", cwd=tmp_path).returncode == 0
    folder = tmp_path / "rover"
    logged = run_robot(folder, "--log")
    assert logged[-1] == "dura: executive of robot 'rover' stopped"
    body = logged[1:-1]
    assert all(LINE.fullmatch(line) or TABLE_ROW.fullmatch(line) for line in body), body
    kinds = [line.split()[1] for line in body if LINE.fullmatch(line)]
    for kind in ("GOAL_ADDED", "PLAN", "START", "END", "GOAL_ACHIEVED"):
        assert kind in kinds, (kind, body)
    assert kinds.index("GOAL_ADDED") < kinds.index("PLAN") < kinds.index("GOAL_ACHIEVED")
    assert any("drive(base, hall)" in line for line in body if TABLE_ROW.fullmatch(line))
    # the same run in a pipe without --log: the first line and the last
    (folder / ".dura").rename(tmp_path / "first-run")
    quiet = run_robot(folder)
    assert len(quiet) == 2 and quiet[1] == "dura: executive of robot 'rover' stopped", quiet


def run_on_a_terminal(folder: Path, *flags: str) -> str:
    """Run the robot of ``folder`` with its output on a pseudo-terminal until its goal is
    achieved; what the terminal showed."""
    endpoint = free_endpoint()
    env = {**os.environ, "PYTHONPATH": str(ROOT), "DURA_TIME_SCALE": "10"}
    argv = [sys.executable, "-m", "executive.cli", "run", "robot.yaml", "--endpoint", endpoint]
    leader, follower = pty.openpty()
    shown = b""
    with subprocess.Popen([*argv, *flags], cwd=folder, env=env, stdout=follower) as process:
        os.close(follower)
        try:
            while b"Ctrl-C stops it" not in shown:
                shown += os.read(leader, 4096)
            added = run_dura("goal", "add", "(inspected kitchen)", "--wait", cwd=folder, env=env)
            assert added.returncode == 0, added.stdout + added.stderr
        finally:
            process.send_signal(signal.SIGINT)
        while b"stopped" not in shown:
            try:
                shown += os.read(leader, 4096)
            except OSError:  # the terminal closed with the process
                break
        process.wait(timeout=60)
    os.close(leader)
    return shown.decode(errors="replace")


def test_dura_run_shows_its_log_on_a_terminal_unless_quiet(tmp_path: Path) -> None:
    assert run_dura("new", "rover", cwd=tmp_path).returncode == 0
    folder = tmp_path / "rover"
    shown = run_on_a_terminal(folder)
    assert "GOAL_ACHIEVED" in shown and "PLAN " in shown, shown
    (folder / ".dura").rename(tmp_path / "first-run")
    quiet = run_on_a_terminal(folder, "--quiet")
    assert "GOAL_ADDED" not in quiet and "stopped" in quiet, quiet
