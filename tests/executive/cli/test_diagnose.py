"""``dura diagnose`` as a user runs it: the registry's models from YAML files."""

from __future__ import annotations

import json
from collections.abc import Callable
from pathlib import Path
from subprocess import CompletedProcess

import pytest

from tests.monitoring.diagnosis.cases import CASES, Case

Dura = Callable[..., CompletedProcess[str]]

# A few cases through the whole command; the registry as a whole runs in-process.
SPECIAL = [c for c in CASES if c.exonerate or c.status != "DIAGNOSED" or c.max_card]
CLI_CASES = [*SPECIAL[:5], CASES[1]]


@pytest.mark.parametrize("case", CLI_CASES, ids=lambda c: c.name)
def test_diagnose_prints_the_expected_diagnoses_as_json(
    dura: Dura, case: Case, tmp_path: Path
) -> None:
    model, observations = case.write(tmp_path)
    args = ["diagnose", str(model), "--observations", str(observations), "--json"]
    args += ["--exonerate"] if case.exonerate else []
    args += ["--max-card", str(case.max_card)] if case.max_card is not None else []
    result = dura(*args)
    assert result.returncode == 0, result.stderr
    data = json.loads(result.stdout)
    assert data["status"] == case.status
    assert data["diagnoses"] == sorted(sorted(d) for d in case.expected)


def test_diagnose_explains_itself_for_people(dura: Dura, tmp_path: Path) -> None:
    model, observations = CASES[1].write(tmp_path)
    result = dura("diagnose", str(model), "--observations", str(observations))
    assert result.returncode == 0, result.stderr
    lines = result.stdout.splitlines()
    assert lines[0].startswith("DIAGNOSED: 3 minimal diagnoses")
    assert lines[1] == "failed: frequency[m3]"
    assert lines[2:] == ["  1. N1", "  2. N2", "  3. N3"]


def test_diagnose_reads_the_tug_form_of_a_model(dura: Dura, tmp_path: Path) -> None:
    (tmp_path / "model.yaml").write_text(
        "nodes:\n"
        "  - {name: node1, sub_topic: [], pub_topic: [/topic1]}\n"
        "  - {name: node2, sub_topic: [/topic1], pub_topic: [/topic2]}\n"
        "observations:\n"
        "  - {type: hz, topics: [/topic1, /topic2]}\n"
        "  - {type: activated, nodes: [node1, node2]}\n"
        "  - {type: timing, topics: [[/topic1, /topic2]]}\n"
    )
    (tmp_path / "obs.yaml").write_text(
        "observations:\n  - {type: hz, resource: /topic2, observation: -1}\n"
        "  - {type: activated, resource: [node2], observation: 1}\n"
    )
    result = dura(
        "diagnose",
        str(tmp_path / "model.yaml"),
        "--observations",
        str(tmp_path / "obs.yaml"),
        "--json",
    )
    assert result.returncode == 0, result.stderr
    assert json.loads(result.stdout) == {"status": "DIAGNOSED", "diagnoses": [["node1"], ["node2"]]}


@pytest.mark.parametrize(
    "bad",
    [
        (
            "nodes:\n  - {name: a, pub_topic: [x]}\nobservers:\n  - {type: hz, resource: [y]}\n",
            "observations: []\n",
            "model.yaml:4",
            "unknown topic 'y'",
        ),
        (
            "nodes:\n  - {name: ABa, pub_topic: [x]}\n",
            "observations: []\n",
            "model.yaml:2",
            "starts with 'AB'",
        ),
        (
            "nodes:\n  - {name: a, pub_topic: [x]}\n  - {name: a}\n",
            "observations: []\n",
            "model.yaml:3",
            "node 'a' is already in the model",
        ),
        (
            "nodes:\n  - {name: a, pub_topic: [x]}\nobservers:\n  - {type: timing, resource: [x]}\n",
            "observations: []\n",
            "model.yaml:4",
            "watches 2 resources, not 1",
        ),
        (
            "nodes:\n  - {name: a, pub_topic: [x], pubtopic: [y]}\n",
            "observations: []\n",
            "model.yaml:2",
            "unknown key 'pubtopic'",
        ),
        (
            "nodes:\n  - {name: a, pub_topic: [x]}\nobservers:\n  - {type: hz, resource: [x]}\n",
            "observations:\n  - {type: timeout, resource: [x], observation: -1}\n",
            "obs.yaml:2",
            "timeout[x]: no such observer",
        ),
        (
            "nodes:\n  - {name: a, pub_topic: [x]}\nobservers:\n  - {type: hz, resource: [x]}\n",
            "observations:\n  - {type: hz, resource: [x], observation: bad}\n",
            "obs.yaml:2",
            "must be an integer",
        ),
        ("nodes: [\n", "observations: []\n", "model.yaml:2", "invalid YAML"),
    ],
    ids=[
        "unknown topic",
        "AB name",
        "duplicate node",
        "arity",
        "unknown key",
        "unknown observer",
        "bad value",
        "syntax",
    ],
)
def test_diagnose_names_file_and_line_of_bad_input_and_exits_1(
    dura: Dura, tmp_path: Path, bad: tuple[str, str, str, str]
) -> None:
    model, observations, where, message = bad
    (tmp_path / "model.yaml").write_text(model)
    (tmp_path / "obs.yaml").write_text(observations)
    result = dura(
        "diagnose", str(tmp_path / "model.yaml"), "--observations", str(tmp_path / "obs.yaml")
    )
    assert result.returncode == 1
    assert result.stderr.startswith(f"dura: {tmp_path / where}: "), result.stderr
    assert message in result.stderr
    assert len(result.stderr.splitlines()) == 1
