"""``dura demo --fleet`` as a user runs it: three real executives, their components and
the fleet's high level with a real planner; the robots deliver in parallel, the one
killed mid-plan is lost and planned around, the others deliver every parcel, once; the
fleet's dashboard, served meanwhile, draws its plan by robot."""

from __future__ import annotations

import json
import os
import re
import subprocess
import sys
import threading
import urllib.request
from pathlib import Path
from typing import IO

import pytest

from executive.cli.demo_timeline import replans
from knowledge.knowledge_base import KnowledgeBase
from tests.conftest import ROOT, wait_for

pytestmark = pytest.mark.slow

STEPS = ("DISPATCH", "START", "ADOPT", "END", "FAIL", "CANCEL")


class Dashboard:
    """The dashboard's address as the demo prints it (on stderr with --json), and the
    robots its plan picture has drawn while the demo ran."""

    def __init__(self, stderr: IO[str] | None) -> None:
        self.url = ""
        self.lines: list[str] = []
        self.robots: set[str] = set()
        self._reader = threading.Thread(target=self._read, args=(stderr,), daemon=True)
        self._reader.start()

    def _read(self, stderr: IO[str] | None) -> None:
        for line in stderr or ():
            self.lines.append(line)
            found = re.search(r"dashboard on http://(\S+)", line)
            if found:
                self.url = found.group(1)  # host:port/?token=...

    def look(self) -> bool:
        """Whether the plan picture draws steps of two robots or more (by robot)."""
        address, _, token = self.url.partition("/?token=")
        try:
            with urllib.request.urlopen(
                f"http://{address}/api/plan.svg?token={token}", timeout=5
            ) as r:
                picture = r.read().decode()
        except OSError:  # no plan yet (404), or the demo has ended
            return False
        self.robots |= set(re.findall(r'data-robot="(\w+)"', picture))
        return len(self.robots) >= 2


def test_the_fleet_demo_delivers_every_parcel_after_one_robot_is_killed(tmp_path: Path) -> None:
    argv = [sys.executable, "-m", "executive.cli", "demo", "--fleet", "--keep",
            str(tmp_path / "run"), "--json", "--dashboard", "0"]  # fmt: skip
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    with subprocess.Popen(argv, cwd=ROOT, env=env, text=True, stdout=subprocess.PIPE,
                          stderr=subprocess.PIPE) as demo:  # fmt: skip
        page = Dashboard(demo.stderr)
        assert wait_for(lambda: page.url, 120), "".join(page.lines)
        # the fleet's plan by robot, while the robots work
        assert wait_for(page.look, 60), page.robots
        out, _ = demo.communicate(timeout=300)
    assert demo.returncode == 0, "".join(page.lines)
    report = json.loads(out)
    assert report["ok"]
    assert [g["state"] for g in report["goals"]] == ["achieved"] * 3
    killed = report["killed"]
    assert report["lost"] == [killed]
    robots = {r["robot"]: r for r in report["robots"]}
    assert sorted(robots) == ["r1", "r2", "r3"]
    assert not robots[killed]["available"] and robots[killed]["failed"] >= 1
    events = report["events"]

    # every plan step names its robot, the robot its action's robot parameter names
    for e in events:
        if e["kind"] in STEPS:
            assert f"({e['robot']}," in e["subject"], e
    # the robots worked in parallel: a step of one started while another's ran
    running: dict[str, int] = {}
    overlapped = False
    for e in events:
        if e["kind"] == "START":
            overlapped |= any(r != e["robot"] and n > 0 for r, n in running.items())
            running[e["robot"]] = running.get(e["robot"], 0) + 1
        elif e["kind"] in ("END", "FAIL", "CANCEL") and running.get(e["robot"]):
            running[e["robot"]] -= 1
    assert overlapped

    # killed mid-plan: its step failed, the fleet lost it, and it did nothing after
    lost = next(i for i, e in enumerate(events) if e["kind"] == "ROBOT_LOST")
    assert events[lost]["robot"] == killed
    assert any(e["kind"] == "FAIL" and e.get("robot") == killed for e in events)
    assert not [e for e in events[lost:] if e["kind"] == "END" and e.get("robot") == killed]
    # the others delivered every parcel, each once, where its goal wanted it
    drops = [e["subject"] for e in events if e["kind"] == "END" and e["data"]["action"] == "drop"]
    assert sorted(d.split(", ", 1)[1] for d in drops) == [
        "parcel1, lab)",
        "parcel2, office)",
        "parcel3, lab)",
    ]
    assert all(g["robot"] not in (killed, None) for g in report["goals"])

    # the replans and plans as the fleet's knowledge base logged them
    with KnowledgeBase(tmp_path / "run" / "fleet" / "depot.db", readonly=True) as kb:
        logged = kb.events()
        facts = {f"({f.name} {' '.join(f.args)})" for f in kb.facts() if f.name == "crate_at"}
    assert report["replans"] == len(replans(logged)) >= 1
    started = [e for e in logged if e.kind == "PLAN_START"]
    assert [p["id"] for p in report["plans"]] == [int(e.subject[5:]) for e in started]
    assert facts == {
        "(crate_at parcel1 lab)",
        "(crate_at parcel2 office)",
        "(crate_at parcel3 lab)",
    }
