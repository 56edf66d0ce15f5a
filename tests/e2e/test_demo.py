"""``dura demo``, the main job, as a user runs it: every goal achieved after lidar
became permanently faulty and move_to switched to the camera."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

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
