"""``dura events --follow`` shows every event of the log, in order, under load."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import threading
from pathlib import Path

from executive.bus.api import planning
from executive.testing.harness import RobotProcess
from tests.conftest import ROOT, USECASE, wait_for

EVENTS = 400  # fact changes made while following, each an event, as fast as they go


def test_following_events_misses_none_under_load(tmp_path: Path) -> None:
    with RobotProcess(USECASE, tmp_path / "robot") as robot:
        follower = subprocess.Popen(
            [sys.executable, "-m", "executive.cli", "events", "--follow", "--json", "-n", "1",
             "--robot", str(USECASE), "--endpoint", robot.endpoint],
            cwd=robot.folder, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
            env={**os.environ, "PYTHONPATH": str(ROOT)},
        )  # fmt: skip
        printed: list[int] = []
        reader = threading.Thread(target=_read, args=(follower, printed), daemon=True)
        reader.start()
        try:
            # the newest event printed: the follower prints every event from there on
            assert wait_for(lambda: bool(printed), timeout=30)
            writers = [
                threading.Thread(target=_change_facts, args=(robot, n, EVENTS // 4))
                for n in range(4)
            ]
            for writer in writers:
                writer.start()
            for writer in writers:
                writer.join()
            stored = robot.events()
            newest = stored[-1].id
            assert wait_for(lambda: bool(printed) and printed[-1] >= newest, timeout=30)
        finally:
            follower.send_signal(signal.SIGINT)
            err = follower.communicate(timeout=10)[1]
            reader.join(timeout=5)
        assert "Traceback" not in err
        first = printed[0]
        assert printed == [e.id for e in stored if first <= e.id <= printed[-1]]
        seen = set(printed)
        assert sum(1 for e in stored if e.id in seen and e.kind == "STATE_SET") == EVENTS


def _read(follower: subprocess.Popen[str], printed: list[int]) -> None:
    assert follower.stdout is not None
    for line in follower.stdout:
        if line.startswith("{"):
            printed.append(json.loads(line)["id"])


def _change_facts(robot: RobotProcess, writer: int, count: int) -> None:
    for n in range(count):
        fact = "(robot_at lab)" if (n + writer) % 2 else "(robot_at office)"
        planning.STATE_SET.call(robot.bus, planning.FactChange(fact))
