"""``dura rules check`` as a user runs it."""

from __future__ import annotations

import json
from collections.abc import Callable
from pathlib import Path
from subprocess import CompletedProcess

import pytest

Dura = Callable[..., CompletedProcess[str]]

GOOD = """rules:
  - type: restart
    name: restart_lidar
    component: lidar
    positive_observations:
      - {type: hz, resource: scan, observation: -1, occurrences: 3, window_size: 5}
    recall_duration: 10.0
  - type: email
    host: localhost
    from_address: robot@localhost
    to_address: ops@localhost
    positive_possible_faulty_resources: [{resource: lidar}]
    single_shot: true
"""


def test_rules_check_accepts_a_thesis_rules_file(dura: Dura, tmp_path: Path) -> None:
    (tmp_path / "rules.yaml").write_text(GOOD)
    result = dura("rules", "check", str(tmp_path / "rules.yaml"))
    assert result.returncode == 0, result.stderr
    assert result.stdout.splitlines() == [
        f"{tmp_path / 'rules.yaml'}: valid: 2 rules",
        "  restart_lidar: restart lidar",
        "  rule2: mail ops@localhost via localhost:25",
    ]
    data = json.loads(dura("rules", "check", "--json", str(tmp_path / "rules.yaml")).stdout)
    assert data["valid"] is True and [r["name"] for r in data["rules"]] == [
        "restart_lidar",
        "rule2",
    ]


@pytest.mark.parametrize(
    ("text", "line", "message"),
    [
        (
            "rules:\n  - type: restrt\n    component: x\n",
            2,
            "unknown action type 'restrt' (did you mean 'restart'?)",
        ),
        ("rules:\n  - type: process\n    process: kill -9 1\n", 3, "must be an argv list"),
        ("rules:\n  - type: log\n", 2, "has no condition"),
        (
            "rules:\n  - type: log\n    positive_observations: [{type: hz, resource: s, occurrences: 3, window_size: 2}]\n",
            3,
            "'window_size' of 'positive_observations' of rule 'rule1' (2) is smaller than 'occurrences' (3)",
        ),
        (
            "rules:\n  - type: log\n    positive_observations: [{type: hzz, resource: s}]\n",
            3,
            "unknown observer type 'hzz'",
        ),
        (
            "rules:\n  - type: log\n    recal_duration: 3\n    positive_observations: [{type: hz, resource: s}]\n",
            3,
            "unknown key 'recal_duration'",
        ),
        (
            "rules:\n  - {type: log, name: a, positive_observations: [{type: hz, resource: s}]}\n"
            "  - {type: log, name: a, positive_observations: [{type: hz, resource: s}]}\n",
            3,
            "rule 'a' is defined twice",
        ),
        ("rules: [\n", 2, "invalid YAML"),
    ],
    ids=[
        "unknown action",
        "shell string",
        "no condition",
        "window",
        "observer type",
        "unknown key",
        "duplicate",
        "syntax",
    ],
)
def test_rules_check_names_file_line_and_problem(
    dura: Dura, tmp_path: Path, text: str, line: int, message: str
) -> None:
    (tmp_path / "rules.yaml").write_text(text)
    result = dura("rules", "check", str(tmp_path / "rules.yaml"))
    assert result.returncode == 1
    assert f"{tmp_path / 'rules.yaml'}:{line}: " in result.stderr and message in result.stderr, (
        result.stderr
    )
    assert "Traceback" not in result.stderr


def test_rules_check_reports_an_asp_error_with_file_line_and_column(
    dura: Dura, tmp_path: Path
) -> None:
    (tmp_path / "rules.yaml").write_text("rules:\n  - {type: log, name: x}\nasp: [more.lp]\n")
    (tmp_path / "more.lp").write_text('trigger("x") :- status("DIAGNOSED").\nbad(.\n')
    result = dura("rules", "check", str(tmp_path / "rules.yaml"))
    assert result.returncode == 1
    assert f"{tmp_path / 'more.lp'}:2:5: syntax error" in result.stderr
