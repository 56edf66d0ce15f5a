"""``dura demo --fleet`` as a user runs it: three real executives, their components and
the fleet's high level with a real planner; the robots deliver in parallel, the one
killed mid-plan is lost and planned around, the others deliver every parcel, once."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from executive.cli.demo_timeline import replans
from knowledge.knowledge_base import KnowledgeBase
from tests.conftest import run_dura

pytestmark = pytest.mark.slow

STEPS = ("DISPATCH", "START", "ADOPT", "END", "FAIL", "CANCEL")


def test_the_fleet_demo_delivers_every_parcel_after_one_robot_is_killed(tmp_path: Path) -> None:
    done = run_dura("demo", "--fleet", "--keep", str(tmp_path / "run"), "--json", timeout=300)
    assert done.returncode == 0, done.stderr
    report = json.loads(done.stdout)
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
