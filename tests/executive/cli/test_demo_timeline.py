"""What ``dura demo`` prints, from events as the executive logs them (no robot): each
executed plan as it starts with what it replaces and why, a rule after the diagnosis it
fired on, one line per component start, and replans counted from the log."""

from __future__ import annotations

import io
import json
import logging
import re
from typing import Any

from executive.bus.message import Message
from executive.bus.schema import plain
from executive.cli.demo_timeline import Timeline, WarningLines, replans
from knowledge.records import Event

T0 = 1_700_000_000.0


def message(payload: dict[str, Any]) -> Message:
    return Message("dura/usecase/events", json.dumps(payload).encode())


class Log:
    """Events with ids and stamps in the log's order."""

    def __init__(self) -> None:
        self.events: list[Event] = []

    def __call__(self, at: float, kind: str, subject: str, **data: Any) -> Event:
        event = Event(len(self.events) + 1, T0 + at, kind, subject, data)
        self.events.append(event)
        return event


def scenario() -> Log:
    log = Log()
    log(0.1, "GOAL_ADDED", "goal 1", expression="(picture_taken lab)")
    log(0.2, "PLANNING", "goal planner", reason="goal 1 added", goals=[1], blocked=[])
    log(0.3, "PLAN_STORED", "plan 1", steps=1, engine="kairos")
    log(0.3, "PLAN_START", "plan 1", steps=1, goals=[1])
    log(0.4, "COMPONENT_STARTING", "move_to", pid=7)
    log(0.5, "COMPONENT_READY", "move_to", pid=7)
    log(0.6, "COMPONENT_PAUSED", "move_to", pid=7)
    log(0.7, "PLANNING", "goal planner", reason="goal 2 added", goals=[1, 2], blocked=[])
    log(0.8, "PLAN_STORED", "plan 2", steps=2, engine="kairos", replaces=1)
    log(0.8, "PLAN_START", "plan 2", steps=2, goals=[1, 2])
    log(0.9, "COMPONENT_READY", "move_to", pid=7)  # resumed: not a second start
    log(1.2, "RULE_FIRED", "restart_lidar", action="restart lidar", faulty=["lidar"])
    log(1.5, "REPLAN", "plan 2", reason="step move_to(dock, lab) failed: blocked")
    log(1.6, "PLAN_STORED", "plan 3", steps=1, engine="kairos")
    log(1.6, "PLAN_START", "plan 3", steps=1, goals=[1, 2])
    return log


def test_replans_are_the_plans_that_replaced_one_or_followed_a_failed_one() -> None:
    assert replans(scenario().events) == [2, 3]
    assert replans(scenario().events[:4]) == []


def test_the_timeline_shows_each_plan_as_it_starts_and_keeps_causes_before_effects() -> None:
    out = io.StringIO()
    timeline = Timeline(quiet=False, everything=False, out=out)
    timeline.start = T0
    log = scenario()
    for event in log.events:
        if event.kind == "RULE_FIRED":  # the rule's event comes before the diagnosis
            timeline.on_event(message(plain(event)))
            diagnosis = {"status": "DIAGNOSED", "diagnoses": [["lidar"]],
                         "failed": [{"type": "timeout", "resource": ["scan"]}], "stamp": T0 + 1.1}  # fmt: skip
            timeline.on_diagnoses(message(diagnosis))
        else:
            timeline.on_event(message(plain(event)))
    timeline.close()
    lines = out.getvalue().splitlines()
    heads = [line.split("PLAN", 1)[1].strip() for line in lines if "  PLAN  " in line]
    assert heads == [
        "plan 1 by ? for goal 1: 0 steps, 0 s",
        "plan 2 by ? for goals 1, 2: 0 steps, 0 s; replaces plan 1: goal 2 added",
        "plan 3 by ? for goals 1, 2: 0 steps, 0 s; the plan before failed: "
        "step move_to(dock, lab) failed: blocked",
    ]
    kinds = [line.split()[1] for line in lines if line[:1] == " " and line.split()[0].endswith("s")]
    assert kinds.index("DIAGNOSIS") < kinds.index("RULE_FIRED")
    assert kinds.count("COMPONENT_READY") == 1
    assert [p["id"] for p in timeline.plans] == [1, 2, 3]
    assert not any("[[" in line or "{'" in line for line in lines)


def test_a_warning_is_a_line_of_the_timeline_in_its_format() -> None:
    out = io.StringIO()
    timeline = Timeline(quiet=False, everything=False, out=out)
    logger = logging.getLogger("dura.test_timeline")
    logger.propagate = False
    logger.addHandler(WarningLines(timeline))
    try:
        logger.info("not shown")
        logger.warning("'%s' ignored SIGTERM", "lidar")
    finally:
        logger.handlers.clear()
        logger.propagate = True
    timeline.close()
    assert re.fullmatch(
        r" +\d+\.\ds  WARNING +dura\.test_timeline: 'lidar' ignored SIGTERM\n", out.getvalue()
    )


def test_each_task_is_named_with_its_step_the_first_time_a_line_names_it() -> None:
    out = io.StringIO()
    timeline = Timeline(quiet=False, everything=False, out=out)
    timeline.start = T0
    log = Log()
    log(0.1, "TASK_REQUESTED", "task 1 move_to(dock, lab)")
    log(0.2, "CONFIGURATION", "lidar", start=["lidar"], stop=[], resume=[],
        why="task 1 requested")  # fmt: skip
    log(0.3, "TASK_STARTED", "task 1 move_to(dock, lab)")
    log(0.4, "START", "move_to(dock, lab)", plan=1, step=0, undo=[])
    log(1.0, "TASK_REQUESTED", "task 2 take_picture(lab)")
    log(1.1, "TASK_STARTED", "task 2 take_picture(lab)")
    log(1.2, "START", "take_picture(lab)", plan=1, step=1, undo=[])
    log(1.5, "CONFIGURATION", "nothing", start=[], stop=["lidar"], resume=[],
        why="task 2 succeeded")  # fmt: skip
    for event in log.events:
        timeline.on_event(message(plain(event)))
    timeline.close()
    texts = [line.split(None, 2)[2] for line in out.getvalue().splitlines()]
    assert texts == [
        "task 1 move_to(dock, lab) requested: start lidar",
        "move_to(dock, lab) (plan 1, step 0, task 1)",
        "take_picture(lab) (plan 1, step 1, task 2)",
        "task 2 succeeded: stop lidar; nothing runs",
    ]


def test_a_fleets_timeline_names_the_robot_of_each_step_and_of_each_robot_event() -> None:
    out = io.StringIO()
    timeline = Timeline(
        quiet=False,
        everything=False,
        out=out,
        robots=["r1", "r2"],
        robot_of=lambda action, args: args[0] if args and args[0] in ("r1", "r2") else None,
    )
    timeline.start = T0
    log = Log()
    log(0.1, "GOAL_ADDED", "goal 1", expression="(crate_at parcel1 lab)")
    log(0.2, "START", "drive(r1, dock1, store)", plan=1, step=0, action="drive",
        args=["r1", "dock1", "store"])  # fmt: skip
    log(0.3, "ROBOT_LOST", "r2", reason="its executive vanished")
    for event in log.events:
        timeline.on_event(message(plain(event)))
    timeline.close()
    texts = [
        re.split(r"\s{2,}", line.strip(), maxsplit=2)[1:] for line in out.getvalue().splitlines()
    ]
    assert texts == [
        ["GOAL_ADDED", "goal 1: (crate_at parcel1 lab)"],
        ["START", "r1  drive(r1, dock1, store) (plan 1, step 0)"],
        ["ROBOT_LOST", "r2  robot r2 is unavailable: its executive vanished"],
    ]
