"""Output reads as a person writes: counts agree with their nouns, numbers are rounded
and carry their units the same way in every view, tables start on the first line, and
an event kind dura never logs is refused with the kinds it does log."""

from __future__ import annotations

import io
import re
from pathlib import Path

from executive.bus.api.planning import StatusReply
from executive.bus.api.tasks import TaskStart
from executive.bus.event_kinds import KINDS
from executive.bus.reports import DiagnosisInfo, ExecutionStatus
from executive.cli.observe import _measured
from executive.cli.status import print_status
from knowledge.knowledge_base import KnowledgeBase
from tests.conftest import run_dura


def test_an_unknown_event_kind_is_refused_with_the_kinds_dura_logs(tmp_path: Path) -> None:
    refused = run_dura("events", "--db", str(tmp_path / "any.db"), "--kind", "bogus")
    assert refused.returncode == 2
    assert "no event is of kind 'bogus'; the kinds are: " in refused.stderr
    assert all(kind in refused.stderr for kind in KINDS)


def test_a_kind_may_be_written_in_lower_case(tmp_path: Path) -> None:
    path = tmp_path / "r.db"
    with KnowledgeBase(path) as kb:
        kb.log_event("GOAL_ADDED", "goal 1", {"expression": "(robot_at lab)"})
        kb.log_event("FAULT", "lidar", {"count": 1, "permanent": False, "reason": "exited"})
    shown = run_dura("events", "--db", str(path), "--kind", "fault")
    assert shown.returncode == 0, shown.stderr
    assert [line.split(maxsplit=1)[1] for line in shown.stdout.splitlines()] == [
        "FAULT                  lidar: fault 1: exited"
    ]


def test_status_starts_with_its_first_title_and_reads_its_diagnosis() -> None:
    out = io.StringIO()
    diagnosis = DiagnosisInfo(
        "DIAGNOSED", (("lidar",),), failed=({"type": "timeout", "resource": ["scan"]},)
    )
    print_status(StatusReply("usecase", [], None, ExecutionStatus(), diagnosis, []), out)
    lines = out.getvalue().splitlines()
    assert lines[0] == "robot usecase: goals"
    assert lines[-1] == "diagnosis: DIAGNOSED: lidar (failed: timeout[scan])"


def test_kb_show_gives_deadlines_in_seconds_and_events_as_sentences(tmp_path: Path) -> None:
    path = tmp_path / "r.db"
    with KnowledgeBase(path) as kb:
        kb.add_goal("(robot_at dock)", deadline=60.0)
        kb.register_component("lidar", 10)
        kb.record_fault("lidar", "crashed", max_faults=3)
    text = run_dura("kb", "show", "--db", str(path), "--events", "1")
    assert text.returncode == 0, text.stderr
    assert re.search(r"^1 +pending +0 +60 s +user +\(robot_at dock\)$", text.stdout, re.M)
    assert "last 1 event\n" in text.stdout
    assert re.search(r"FAULT +lidar: fault 1: crashed$", text.stdout, re.M)
    assert "{'" not in text.stdout and "[[" not in text.stdout


def test_measured_values_are_rounded_and_carry_their_units() -> None:
    assert _measured("frequency", 9.998) == "frequency 10 Hz"
    assert _measured("silence", 0.05962) == "silence 0.06 s"
    assert _measured("memory", 3 << 20) == "memory 3 MiB"
    assert _measured("score", 0.5) == "score 0.5"


def test_a_task_started_by_hand_is_named_by_its_goal_fields() -> None:
    assert TaskStart("move_to", {"start": "dock", "target": "lab"}).label == (
        "move_to(start=dock, target=lab)"
    )
    assert TaskStart("take_picture").label == "take_picture"


def test_counts_agree_with_their_nouns(tmp_path: Path) -> None:
    rules = tmp_path / "rules.yaml"
    rules.write_text(
        "rules:\n  - {type: log, name: note, message: hello,\n"
        "     positive_possible_faulty_resources: [{resource: lidar}]}\n"
    )
    checked = run_dura("rules", "check", str(rules))
    assert checked.returncode == 0, checked.stderr
    assert checked.stdout.splitlines()[0].endswith(": valid: 1 rule")
