"""Hostile YAML is refused at once with one line naming the file and the place."""

from __future__ import annotations

from pathlib import Path

import pytest

from knowledge.finding import Report
from knowledge.yamlsource import MAX_BYTES, compose
from tests.conftest import run_dura

BOMB = "".join(
    f"{name}: &{name} [{', '.join([f'*{prev}'] * 9) if prev else ', '.join(['lol'] * 9)}]\n"
    for prev, name in zip(["", "a", "b", "c", "d", "e", "f", "g", "h"], "abcdefghi", strict=True)
)
DEEP_FLOW = "robot: " + "[" * 3000 + "]" * 3000 + "\n"
DEEP_BLOCK = "".join("  " * i + f"k{i}:\n" for i in range(200)) + "  " * 200 + "end: 1\n"


@pytest.mark.timeout(10)  # a hostile file used to hang the reader
@pytest.mark.parametrize(
    ("text", "message"),
    [
        (BOMB, "its aliases expand to more than 100000 values (a YAML bomb?)"),
        (DEEP_FLOW, "invalid YAML"),
        (DEEP_BLOCK, "nested more than 64 levels deep"),
        ("robot: " + "x" * (MAX_BYTES + 1), "too large: 1.0 MiB (at most 1.0 MiB)"),
    ],
    ids=["alias bomb", "deep flow", "deep block", "too large"],
)
def test_a_hostile_document_is_refused_within_a_second(
    tmp_path: Path, text: str, message: str
) -> None:
    path = tmp_path / "robot.yaml"
    path.write_text(text)
    report = Report(str(path))
    assert compose(path, report) is None
    assert len(report.findings) == 1
    assert message in report.findings[0].message


def test_the_line_of_a_too_deep_nesting_is_named(tmp_path: Path) -> None:
    path = tmp_path / "robot.yaml"
    path.write_text(DEEP_BLOCK)
    report = Report(str(path))
    compose(path, report)
    assert str(report.findings[0]).startswith(f"{path}:65: ")


@pytest.mark.parametrize("text", [BOMB, DEEP_FLOW, DEEP_BLOCK], ids=["bomb", "flow", "block"])
def test_dura_validate_answers_a_hostile_file_with_one_line(tmp_path: Path, text: str) -> None:
    path = tmp_path / "robot.yaml"
    path.write_text(text)
    done = run_dura("validate", str(path), timeout=30)
    assert done.returncode == 1
    lines = done.stdout.strip().splitlines() + done.stderr.strip().splitlines()
    assert len([line for line in lines if str(path) in line]) == 1, lines
    assert "Traceback" not in done.stderr
