"""The replies of the bus API carry typed records, and the JSON on the wire is what it
was when they carried dicts: each reply in ``replies.json`` (as an executive sent it
before the records, trimmed) reads into its records and writes back the same JSON, key
for key and in the same order."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import pytest

from executive.bus.api import components, monitoring, planning, tasks
from executive.bus.reports import ComponentEntry, DiagnosisInfo, ExecutorTask
from executive.bus.verb import Verb
from knowledge.records import Event, Goal, GoalState, Plan

REPLIES: dict[str, dict[str, Any]] = json.loads(
    (Path(__file__).parent / "replies.json").read_text(encoding="utf-8")
)
VERBS = {
    v.key: v
    for module in (components, monitoring, planning, tasks)
    for v in vars(module).values()
    if isinstance(v, Verb)
}


@pytest.mark.parametrize("name", sorted(REPLIES))
def test_a_reply_reads_into_records_and_writes_the_same_json(name: str) -> None:
    sent = REPLIES[name]["reply"]
    reply = VERBS[REPLIES[name]["verb"]].reply.from_payload(sent)
    assert json.dumps(reply.to_payload()) == json.dumps(sent)


def test_the_status_reply_is_read_by_attribute() -> None:
    status = planning.StatusReply.from_payload(REPLIES["status_end"]["reply"])
    assert all(isinstance(g, Goal) for g in status.goals)
    assert status.goals[0].state is GoalState.ACHIEVED
    assert isinstance(status.plan, Plan) and status.plan.steps[0].action == "move_to"
    assert isinstance(status.tasks, list) and isinstance(status.tasks[0], ExecutorTask)
    assert isinstance(status.components, list)
    assert isinstance(status.components[0], ComponentEntry)
    assert status.faults[0].name == "cam" and status.faults[0].fault_count == 1
    assert status.planning is not None and status.planning.phase is not None
    assert status.diagnosis is None  # none yet: the wire says {}


def test_a_section_of_a_service_that_did_not_answer_says_why() -> None:
    status = planning.StatusReply.from_payload(REPLIES["status_unanswered"]["reply"])
    assert status.tasks == planning.Unanswered("the task executor is starting")
    assert status.components == planning.Unanswered("the launcher is starting")


def test_a_diagnosis_in_the_status_is_a_record() -> None:
    sent = {**REPLIES["status_start"]["reply"],
            "diagnoses": {"status": "DIAGNOSED", "diagnoses": [["lidar"]], "conflicts": [],
                          "failed": [{"type": "timeout", "resource": ["scan"]}],
                          "elapsed": 0.01, "stamp": 5.0}}  # fmt: skip
    status = planning.StatusReply.from_payload(sent)
    assert status.diagnosis == DiagnosisInfo(
        "DIAGNOSED", (("lidar",),), (), ({"type": "timeout", "resource": ["scan"]},), 0.01, 5.0
    )
    assert json.dumps(status.to_payload()) == json.dumps(sent)


def test_events_and_facts_are_records() -> None:
    events = planning.EventsReply.from_payload(REPLIES["events"]["reply"]).events
    assert all(isinstance(e, Event) for e in events)
    assert events[0].kind == "EXECUTIVE_STARTED" and events[0].data["time_scale"] == 5.0
    fact = planning.FactReply.from_payload(REPLIES["state_set"]["reply"]).fact
    assert (fact.name, fact.args, fact.value, fact.text) == (
        "travel_time",
        ("dock", "lab"),
        7.0,
        "(= (travel_time dock lab) 7)",
    )
