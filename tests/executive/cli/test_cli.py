"""The dura command line as a user runs it: exit codes, one-line errors, --json."""

from __future__ import annotations

import json
import re
from collections.abc import Callable
from pathlib import Path
from subprocess import CompletedProcess

import pytest

from knowledge.knowledge_base import KnowledgeBase
from knowledge.records import Fact
from tests.knowledge.robot_cases import BROKEN_ROBOTS, BrokenRobot

Dura = Callable[..., CompletedProcess[str]]


def test_validate_accepts_the_use_case(dura: Dura) -> None:
    result = dura("validate", "examples/usecase/robot.yaml")
    assert result.returncode == 0, result.stderr
    assert result.stdout.startswith("examples/usecase/robot.yaml: valid: robot 'usecase'")
    assert result.stderr == ""


@pytest.mark.parametrize("case", BROKEN_ROBOTS, ids=lambda c: c.name)
def test_validate_names_file_line_and_problem_and_exits_1(
    dura: Dura, case: BrokenRobot, tmp_path: Path
) -> None:
    path = case.write(tmp_path)
    result = dura("validate", str(path))
    assert result.returncode == 1
    assert "Traceback" not in result.stderr
    expected_file = "domain.pddl" if case.in_domain else "robot.yaml"
    place = re.escape(f"{tmp_path / expected_file}:{case.expected_line(tmp_path)}")
    lines = result.stderr.splitlines()
    located = [line for line in lines if re.match(rf"{place}(:\d+)?: ", line)]  # PDDL: :col
    assert any(case.message in line for line in located), lines


def test_validate_json_lists_the_findings(dura: Dura, tmp_path: Path) -> None:
    path = BROKEN_ROBOTS[1].write(tmp_path)
    result = dura("validate", "--json", str(path))
    assert result.returncode == 1
    data = json.loads(result.stdout)
    assert data["valid"] is False and data["errors"] == 1
    assert data["findings"][0]["severity"] == "error"
    assert "laser_scna" in data["findings"][0]["message"]


@pytest.mark.parametrize(
    "args",
    [("validate",), ("nonsense",), ("validate", "a.yaml", "--bogus"), ("kb",), ()],
    ids=["missing argument", "unknown command", "unknown flag", "missing subcommand", "nothing"],
)
def test_a_usage_error_is_one_line_and_exits_2(dura: Dura, args: tuple[str, ...]) -> None:
    result = dura(*args)
    assert result.returncode == 2
    assert len(result.stderr.strip().splitlines()) == 1, result.stderr
    assert "error:" in result.stderr


def test_a_missing_file_is_one_line_and_exits_1(dura: Dura, tmp_path: Path) -> None:
    result = dura("validate", str(tmp_path / "none.yaml"))
    assert result.returncode == 1
    assert (
        result.stderr.strip() == f"{tmp_path / 'none.yaml'}: cannot read: No such file or directory"
    )


def test_every_command_has_help(dura: Dura) -> None:
    for args in (
        ("--help",),
        ("validate", "--help"),
        ("kb", "show", "--help"),
        ("version", "--help"),
    ):
        result = dura(*args)
        assert result.returncode == 0 and "usage: dura" in result.stdout


def test_kb_show_prints_a_knowledge_base_readably_and_as_json(dura: Dura, tmp_path: Path) -> None:
    path = tmp_path / "r.db"
    with KnowledgeBase(path) as kb:
        kb.add_goal("(picture_taken lab)", priority=2)
        kb.set_fact(Fact("robot_at", ("dock",)))
        kb.register_component("lidar", 10)
        kb.record_fault("lidar", "crashed", max_faults=3)
    text = dura("kb", "show", "--db", str(path))
    assert text.returncode == 0, text.stderr
    assert "(picture_taken lab)" in text.stdout and "(robot_at dock)" in text.stdout
    assert "GOAL_ADDED" in text.stdout and "FAULT" in text.stdout
    data = json.loads(dura("kb", "show", "--db", str(path), "--json").stdout)
    assert data["goals"][0]["expression"] == "(picture_taken lab)"
    assert data["components"][0] == {
        **data["components"][0],
        "name": "lidar",
        "fault_count": 1,
        "permanent_fault": False,
    }


def test_kb_show_finds_the_robots_knowledge_base_in_the_working_folder(
    dura: Dura, tmp_path: Path, usecase_path: Path
) -> None:
    missing = dura("kb", "show", str(usecase_path), cwd=tmp_path)
    assert missing.returncode == 1
    assert (
        missing.stderr.strip()
        == f"dura: {tmp_path / '.dura' / 'usecase.db'}: no knowledge base here"
    )
    with KnowledgeBase(tmp_path / ".dura" / "usecase.db") as kb:
        kb.add_goal("(robot_at dock)")
    found = dura("kb", "show", str(usecase_path), "--json", cwd=tmp_path)
    assert json.loads(found.stdout)["goals"][0]["expression"] == "(robot_at dock)"


def test_version_names_the_engines(dura: Dura) -> None:
    data = json.loads(dura("version", "--json").stdout)
    assert data["dura"] == "0.2.0"
    for name in ("unified-planning", "up-kairos", "clingo", "eclipse-zenoh"):
        assert data[name] != "not installed"


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (
            ["goal", "add", "(robot_at dock)", "--priority", "99999999999999999999999"],
            "argument --priority: must be a whole number from -1000000000 to 1000000000",
        ),
        (["goal", "add", "(robot_at dock)", "--deadline", "nan"], "'nan' is not a finite number"),
        (["goal", "show", "0"], "argument ID: must be an id"),
        (
            ["diagnose", "m.yaml", "--observations", "o.yaml", "--timeout", "-1"],
            "--timeout: must be",
        ),
        (["task", "start", "move_to", "--earliest", "-2"], "argument --earliest: must be 0 and"),
        (["events", "-n", "-5"], "argument -n/--lines: must be a whole number from 0"),
        (["run", "r.yaml", "--grace", "inf"], "argument --grace: 'inf' is not a finite number"),
        (
            ["component", "logs", "lidar", "-n", "x"],
            "argument -n/--lines: 'x' is not a whole number",
        ),
    ],
)
def test_a_bad_number_is_a_usage_error_that_says_what_is_allowed(
    dura: Dura, args: list[str], message: str
) -> None:
    result = dura(*args)
    assert result.returncode == 2
    assert message in result.stderr
    assert len(result.stderr.strip().splitlines()) == 1, result.stderr
