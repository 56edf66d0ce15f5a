"""The sensing: section of a robot description, read and checked against the domain."""

from __future__ import annotations

from pathlib import Path

import pytest
import yaml

from knowledge.validation import validate
from tests.conftest import ROOT

TRANSPORT = ROOT / "examples" / "transport" / "robot.yaml"


def variant(tmp_path: Path, sensing: object) -> Path:
    """The transport robot with another sensing section, beside a copy of its files."""
    data = yaml.safe_load(TRANSPORT.read_text())
    data["domain"] = str((TRANSPORT.parent / data["domain"]).resolve())
    data["problem"] = str(TRANSPORT.parent / data["problem"])
    data["integrity"] = [str(TRANSPORT.parent / p) for p in data["integrity"]]
    data["sensing"] = sensing
    for entry in (TRANSPORT.parent / "components",):
        (tmp_path / entry.name).symlink_to(entry)
    path = tmp_path / "robot.yaml"
    path.write_text(yaml.safe_dump(data, sort_keys=False))
    return path


def rule_line(path: Path, key: str) -> int:
    """The line of a key of the one sensing rule (``topic``: the rule's first line)."""
    lines = path.read_text().splitlines()
    start = next(i for i, text in enumerate(lines, 1) if text.startswith("sensing:"))
    wanted = "- topic:" if key == "topic" else f"{key}:"
    return next(i for i, text in enumerate(lines, 1) if i > start and wanted in text)


def test_the_transport_robot_senses_its_low_battery() -> None:
    result = validate(TRANSPORT)
    assert result.ok, [str(f) for f in result.findings]
    assert result.robot is not None
    (rule,) = result.robot.sensing
    assert (rule.name, rule.topic, rule.path, rule.fact) == (
        "battery_low", "battery", "level", "(battery_low)"
    )  # fmt: skip
    assert (rule.below, rule.clear_above, rule.hold) == (20.0, 30.0, 1.0)
    assert rule.condition == "level < 20 (false again above 30)"


@pytest.mark.parametrize(
    ("rule", "key", "message"),
    [
        (
            {"topic": "batery", "field": "level", "fact": "(battery_low)", "below": 20},
            "topic",
            "sensing rule '(battery_low)' reads topic 'batery', which no component publishes "
            "and the ros2: section does not list (did you mean 'battery'?)",
        ),
        (
            {"topic": "battery", "field": "level", "fact": "(battery_lo)", "below": 20},
            "fact",
            "sensing rule '(battery_lo)': unknown predicate 'battery_lo' (did you mean "
            "'battery_low'?)",
        ),
        (
            {"topic": "battery", "field": "level", "fact": "(robot_at dock lab)", "below": 2},
            "fact",
            "sensing rule '(robot_at dock lab)': 'robot_at' takes 1 argument (?p - place), not 2",
        ),
        (
            {"topic": "battery", "field": "level", "fact": "(robot_at moon)", "below": 2},
            "fact",
            "sensing rule '(robot_at moon)': unknown object 'moon'",
        ),
        (
            {"topic": "battery", "field": "level", "fact": "(holding dock)", "below": 2},
            "fact",
            "sensing rule '(holding dock)': argument 1 of 'holding' must be a crate, but "
            "'dock' is a place",
        ),
        (
            {"topic": "battery", "field": "le vel", "fact": "(battery_low)", "below": 20},
            "field",
            "sensing rule '(battery_low)': field 'le vel' is not a dotted path",
        ),
        (
            {
                "topic": "battery",
                "field": "level",
                "fact": "(battery_low)",
                "below": 20,
                "clear_above": 10,
            },
            "clear_above",
            "sensing rule '(battery_low)': 'clear_above' (10) must not undo 'below' (20)",
        ),
        (
            {"topic": "battery", "field": "level", "fact": "(battery_low)"},
            "topic",
            "sensing rule '(battery_low)': a fact needs exactly one of below, above, equals",
        ),
        (
            {"topic": "battery", "field": "level", "value": "(battery_low)"},
            "value",
            "sensing rule '(battery_low)': unknown function 'battery_low'",
        ),
        (
            {
                "topic": "battery",
                "field": "level",
                "fact": "(battery_low)",
                "below": 20,
                "hold": -1,
            },
            "hold",
            "'hold' of sensing rule '(battery_low)' must be at least 0, not -1",
        ),
    ],
)
def test_a_broken_sensing_rule_is_reported_at_its_line(
    tmp_path: Path, rule: dict[str, object], key: str, message: str
) -> None:
    path = variant(tmp_path, [rule])
    result = validate(path)
    found = [f for f in result.errors if message in f.message]
    assert found, [str(f) for f in result.findings]
    assert (Path(found[0].path).name, found[0].line) == ("robot.yaml", rule_line(path, key))
