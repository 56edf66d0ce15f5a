"""`dura validate`'s checks: the use case is valid; every broken variant is named exactly."""

from __future__ import annotations

from pathlib import Path

import pytest

from knowledge.validation import validate
from tests.knowledge.robot_cases import BROKEN_ROBOTS, BrokenRobot


def test_the_use_case_is_valid_without_warnings(usecase_path: Path) -> None:
    result = validate(usecase_path)
    assert result.ok
    assert result.findings == ()
    assert result.domain is not None
    assert sorted(result.domain.actions) == ["move_to", "take_picture"]


@pytest.mark.parametrize("case", BROKEN_ROBOTS, ids=lambda c: c.name)
def test_a_broken_description_is_reported_with_file_line_and_reason(
    case: BrokenRobot, tmp_path: Path
) -> None:
    path = case.write(tmp_path)
    result = validate(path)
    assert not result.ok
    expected_file = tmp_path / ("domain.pddl" if case.in_domain else "robot.yaml")
    matching = [f for f in result.errors if case.message in f.message]
    assert matching, [str(f) for f in result.findings]
    assert Path(matching[0].path).resolve() == expected_file.resolve()
    assert matching[0].line == case.expected_line(tmp_path)


def test_every_problem_is_reported_not_only_the_first(tmp_path: Path) -> None:
    text = (
        "robot: r\ndomain: d.pddl\nfunctionalities:\n"
        "  a: {command: [x], requires: [nothing], ratng: 2}\n"
        "  b: {command: [x], rating: -1}\n"
    )
    (tmp_path / "d.pddl").write_text("(define (domain d) (:requirements :strips))")
    path = tmp_path / "r.yaml"
    path.write_text(text)
    messages = [f.message for f in validate(path).errors]
    assert any("unknown key 'ratng'" in m for m in messages)
    assert any("requires unknown capability 'nothing'" in m for m in messages)
    assert any("'rating' of functionality 'b' must be at least 0" in m for m in messages)


def test_a_subscription_nobody_publishes_is_a_warning_not_an_error(tmp_path: Path) -> None:
    case = BrokenRobot("", "subscribes: [image]", "subscribes: [images]", "", "")
    result = validate(case.write(tmp_path))
    assert result.ok
    assert any(
        "subscribes to 'images', which no component publishes (did you mean 'image'?)" in w.message
        for w in result.warnings
    )


def test_a_may_subscribe_pattern_no_topic_matches_is_a_warning(tmp_path: Path) -> None:
    opened = "publishes: [image]\n    may_subscribe: ['**/scans', '*/*', odom, 'scan_filtered/**']"
    result = validate(BrokenRobot("", "publishes: [image]", opened, "", "").write(tmp_path))
    assert result.ok
    lines = [w.message for w in result.warnings]
    assert lines == [
        "functionality 'cam' may subscribe to '**/scans', which no topic a component "
        "publishes matches (did you mean 'scan'?)",
        "functionality 'cam' may subscribe to '*/*', which no topic a component publishes matches",
    ], lines


def test_an_action_without_a_task_is_a_warning_against_the_domain(tmp_path: Path) -> None:
    case = BrokenRobot(
        "", "  take_picture:\n    behavior", "  take_pictures:\n    behavior", "", ""
    )
    result = validate(case.write(tmp_path))
    warnings = [w for w in result.warnings if "has no task" in w.message]
    assert len(warnings) == 1
    assert warnings[0].path.endswith("domain.pddl")
    assert warnings[0].line is not None


def test_a_missing_domain_file_is_named(tmp_path: Path) -> None:
    path = tmp_path / "r.yaml"
    path.write_text("robot: r\ndomain: nowhere.pddl\n")
    errors = validate(path).errors
    assert [(e.line, e.message) for e in errors] == [(2, "'domain' names no file: nowhere.pddl")]


def test_an_empty_file_is_an_error(tmp_path: Path) -> None:
    path = tmp_path / "r.yaml"
    path.write_text("")
    assert [e.message for e in validate(path).errors] == ["is empty"]
