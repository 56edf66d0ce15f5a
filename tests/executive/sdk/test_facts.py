"""Facts a component changes reach the robot's world with the component as their source."""

from __future__ import annotations

import os
import time
from pathlib import Path

import pytest

from executive.testing.harness import RobotProcess, robot_variant
from tests.conftest import ROOT, USECASE

pytestmark = pytest.mark.slow


def test_a_fact_a_component_sets_or_unsets_is_logged_with_the_component_as_its_source(
    tmp_path: Path,
) -> None:
    os.environ.setdefault("PYTHONPATH", str(ROOT))
    sensor = {"command": ["python", "-m", "tests.executive.sdk.fact_sensor"]}
    description = robot_variant(
        USECASE, tmp_path / "description", {"functionalities": {"sensor": sensor}}
    )
    with RobotProcess(description, tmp_path / "run") as robot:
        assert robot.request("component/start", {"name": "sensor"})["state"] == "ready"
        changes = [
            (e.kind, e.subject, e.data["source"])
            for e in robot.events()
            if e.kind in ("STATE_SET", "STATE_UNSET")
        ]
        assert changes == [
            ("STATE_UNSET", "(photographable lab)", "sensor"),
            ("STATE_SET", "(photographable lab)", "sensor"),
        ]


def test_a_component_sets_a_fact_that_takes_effect_later(tmp_path: Path) -> None:
    os.environ.setdefault("PYTHONPATH", str(ROOT))
    sensor = {
        "command": ["python", "-m", "tests.executive.sdk.fact_sensor"],
        "params": {"later": 3600.0, "timed": "(photographable dock)"},
    }
    description = robot_variant(
        USECASE, tmp_path / "description", {"functionalities": {"sensor": sensor}}
    )
    with RobotProcess(description, tmp_path / "run") as robot:
        before = time.time()
        assert robot.request("component/start", {"name": "sensor"})["state"] == "ready"
        (timed,) = robot.timed_facts()
        assert str(timed.fact) == "(photographable dock)"
        assert before + 3590 < timed.at < time.time() + 3600
        assert "(photographable dock)" not in robot.facts("photographable")
