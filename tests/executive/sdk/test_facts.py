"""Facts a component changes reach the robot's world with the component as their source."""

from __future__ import annotations

import os
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
