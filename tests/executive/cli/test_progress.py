"""Long commands show what they do now on a terminal, and nothing extra elsewhere.

The commands run in a pseudo-terminal, as in a user's shell: what they write there is
read back as the terminal received it.
"""

from __future__ import annotations

import json
import os
import pty
import re
import select
import signal
import subprocess
import sys
import time
from collections.abc import Callable
from pathlib import Path

from tests.conftest import ROOT, free_endpoint, run_dura

TRANSPORT = ("plan", "--offline", str(ROOT / "domains/transport/domain.pddl"),
             str(ROOT / "examples/transport/parcel.pddl"))  # fmt: skip
USECASE = ROOT / "examples/usecase/robot.yaml"


def on_terminal(
    *args: str,
    cwd: Path,
    until: str | None = None,
    then: Callable[[subprocess.Popen[bytes]], None] | None = None,
    timeout: float = 120.0,
) -> tuple[int, str]:
    """Run dura in a pseudo-terminal: its exit code and everything the terminal got
    (``then`` is called once the output shows ``until``)."""
    leader, follower = pty.openpty()
    env = {**os.environ, "PYTHONPATH": str(ROOT), "COLUMNS": "200"}
    process = subprocess.Popen(
        [sys.executable, "-m", "executive.cli", *args],
        stdin=follower, stdout=follower, stderr=follower, cwd=cwd, env=env,
    )  # fmt: skip
    os.close(follower)
    received = b""
    deadline = time.monotonic() + timeout
    try:
        while time.monotonic() < deadline:
            ready, _, _ = select.select([leader], [], [], 0.5)
            if not ready:
                if process.poll() is not None:
                    break
                continue
            try:
                chunk = os.read(leader, 65536)
            except OSError:  # the terminal is closed: every process on it ended
                break
            if not chunk:
                break
            received += chunk
            if (
                until is not None
                and then is not None
                and until in received.decode(errors="replace")
            ):
                then(process)
                then = None
        return process.wait(timeout=30), received.decode(errors="replace")
    finally:
        if process.poll() is None:
            process.kill()
            process.wait()
        os.close(leader)


def test_plan_offline_says_what_it_does_on_a_terminal_and_takes_the_line_away(
    tmp_path: Path,
) -> None:
    code, shown = on_terminal(*TRANSPORT, cwd=tmp_path)
    assert code == 0, shown
    assert "\rdura: planning with auto (at most 30 s)" in shown  # the default engine
    live, result = shown.rsplit("\r\x1b[K", 1)  # the last thing done to the live line: cleared
    assert "dura: starting the planner" in live
    assert re.match(r"\S*parcel\.pddl: \d+ steps, makespan ", result), result
    assert "\r" not in result.replace("\r\n", "\n")


def test_with_json_or_off_a_terminal_nothing_but_the_result_is_printed(tmp_path: Path) -> None:
    code, shown = on_terminal(*TRANSPORT, "--json", cwd=tmp_path)
    assert code == 0, shown
    assert "dura: " not in shown
    assert json.loads(shown)["status"] == "solved"
    piped = run_dura(*TRANSPORT, cwd=tmp_path)
    assert piped.returncode == 0, piped.stderr
    assert piped.stderr == ""
    assert re.match(r"\S*parcel\.pddl: \d+ steps, makespan ", piped.stdout), piped.stdout


def test_validate_shows_its_checks_on_a_terminal(tmp_path: Path) -> None:
    code, shown = on_terminal("validate", str(USECASE), cwd=tmp_path)
    assert code == 0, shown
    assert "\rdura: checking " in shown and "robot.yaml and its PDDL domain" in shown
    assert re.fullmatch(
        r"\S*robot\.yaml: valid: robot 'usecase'.*\r\n", shown.rsplit("\r\x1b[K", 1)[1]
    )


def test_dura_run_says_what_it_starts_until_the_executive_runs(tmp_path: Path) -> None:
    code, shown = on_terminal(
        "run", str(USECASE), "--endpoint", free_endpoint(), cwd=tmp_path,
        until="Ctrl-C stops it", then=lambda p: p.send_signal(signal.SIGTERM),
    )  # fmt: skip
    assert code == 0, shown
    before, after = shown.split("dura: executive of robot 'usecase' runs on", 1)
    assert "\rdura: opening the bus on tcp/127.0.0.1:" in before
    assert "\rdura: starting the task-executor service" in before
    assert before.endswith("\r\x1b[K"), before[-200:]  # taken away before the result
    assert "stopped" in after
