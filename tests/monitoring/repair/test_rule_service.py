"""The rule service on a real bus: observations and diagnoses in, actions out."""

from __future__ import annotations

import time
from collections.abc import Iterator
from pathlib import Path

import pytest

from executive.bus.keys import DIAGNOSES, OBSERVATIONS
from executive.bus.payloads import DiagnosisInfo
from executive.bus.service import Context
from executive.bus.session import Bus
from knowledge.knowledge_base import KnowledgeBase
from knowledge.robot import load_robot
from monitoring.repair.rule import read_rules
from monitoring.repair.rule_service import RuleService
from tests.conftest import USECASE

RULES = """
rules:
  - type: process
    name: broken
    process: [/nonexistent/tool]
    positive_possible_faulty_resources: [{resource: lidar}]
  - type: log
    name: lidar_down
    file: {log}
    message: "$rule: $faulty"
    positive_possible_faulty_resources: [{resource: lidar}]
  - type: log
    name: scan_slow
    file: {log}
    message: "$rule: $failed"
    positive_observations: [{{type: hz, resource: scan, occurrences: 2}}]
"""


@pytest.fixture
def service(endpoint: str, tmp_path: Path) -> Iterator[tuple[Bus, KnowledgeBase]]:
    robot = load_robot(USECASE)
    path = tmp_path / "rules.yaml"
    path.write_text(
        RULES.replace("{log}", str(tmp_path / "repair.log")).replace("{{", "{").replace("}}", "}")
    )
    with (
        Bus(robot.name, name="executive", endpoint=endpoint, listen=True) as bus,
        KnowledgeBase(tmp_path / "kb.db") as kb,
        Bus(robot.name, name="observer", endpoint=endpoint) as client,
    ):
        rules = RuleService(Context(robot, bus, kb), [read_rules(path)])
        rules.configure()
        rules.activate()
        try:
            yield client, kb
        finally:
            rules.shutdown()


def wait_for_lines(path: Path, count: int, timeout: float = 10.0) -> list[str]:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        lines = path.read_text().splitlines() if path.exists() else []
        if len(lines) >= count:
            return lines
        time.sleep(0.05)
    raise AssertionError(f"{path} has fewer than {count} lines")


def test_rules_fire_on_bus_messages_and_a_failing_action_stops_nothing(
    service: tuple[Bus, KnowledgeBase], tmp_path: Path
) -> None:
    bus, kb = service
    assert bus.wait_for_subscriber(DIAGNOSES) and bus.wait_for_subscriber(OBSERVATIONS)
    bus.publish(DIAGNOSES, DiagnosisInfo("DIAGNOSED", (("lidar",), ("cam",))).to_payload())
    lines = wait_for_lines(tmp_path / "repair.log", 1)
    assert lines[0].endswith("lidar_down: cam, lidar")
    for stamp in (1.0, 2.0):
        bus.publish(
            OBSERVATIONS,
            {"type": "frequency", "resource": ["scan"], "observation": -1, "stamp": stamp},
        )
    lines = wait_for_lines(tmp_path / "repair.log", 2)
    assert lines[1].endswith("scan_slow: frequency[scan]")
    deadline = time.monotonic() + 10
    while not kb.events(kind="RULE_FAILED"):
        assert time.monotonic() < deadline
        time.sleep(0.05)
    failure = kb.events(kind="RULE_FAILED")[0]
    assert failure.subject == "broken"
    assert {e.subject for e in kb.events(kind="RULE_FIRED")} == {
        "broken",
        "lidar_down",
        "scan_slow",
    }
