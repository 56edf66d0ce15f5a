"""``dura demo``, the main job, as a user runs it: every goal achieved after lidar
became permanently faulty and move_to switched to the camera; every plan the robot
executed is shown, replans are counted as the event log has them, and every event
reads without a Python value showing through."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from executive.bus.event_text import describe
from executive.cli.demo_timeline import replans
from knowledge.knowledge_base import KnowledgeBase
from tests.conftest import run_dura

pytestmark = pytest.mark.slow


def test_the_demo_ends_with_every_goal_achieved_after_the_switch_to_the_camera(
    tmp_path: Path,
) -> None:
    done = run_dura("demo", "--keep", str(tmp_path / "run"), "--json", timeout=240)
    assert done.returncode == 0, done.stderr
    report = json.loads(done.stdout)
    assert report["ok"] and all(g["state"] == "achieved" for g in report["goals"])
    lidar = next(c for c in report["faults"] if c["name"] == "lidar")
    assert lidar["permanent_fault"] and lidar["fault_count"] == 3
    events = report["events"]
    injected = [e for e in events if e["kind"] == "FAULT" and e["subject"] == "lidar"]
    assert [e["data"]["count"] for e in injected] == [1, 2, 3]
    switched = [
        e for e in events if e["kind"] == "CONFIGURATION" and "cam_to_lidar" in e["subject"]
    ]
    assert switched, "move_to never ran on cam + cam_to_lidar"
    assert any(
        d["status"] == "DIAGNOSED" and ["lidar"] in d["diagnoses"] for d in report["diagnoses"]
    )
    # every plan it executed, with its steps, as the knowledge base logged it
    with KnowledgeBase(tmp_path / "run" / "usecase.db", readonly=True) as kb:
        logged = kb.events()
    started = [e for e in logged if e.kind == "PLAN_START"]
    assert [p["id"] for p in report["plans"]] == [int(e.subject[5:]) for e in started]
    assert [len(p["steps"]) for p in report["plans"]] == [e.data["steps"] for e in started]
    assert report["replans"] == len(replans(logged)) >= 1  # lidar's fault posts a goal
    for plan in report["plans"][1:]:
        assert plan["replaces"] or plan["why"], plan
    for event in [*events, *logged]:
        text = describe(event)
        assert "[[" not in text and "{'" not in text and "['" not in text, text
