"""Events read as sentences: one line each, with rounded numbers, clocks for stamps, and
no Python value showing through (the events below are as the executive logs them)."""

from __future__ import annotations

import re
from typing import Any

import pytest

from executive.bus.event_kinds import KINDS, WIDTH
from executive.bus.event_text import describe, line


def event(kind: str, subject: str, **data: Any) -> dict[str, Any]:
    return {"id": 1, "stamp": 1_700_000_000.25, "kind": kind, "subject": subject, "data": data}


# every kind as the executive logs it, and how it reads
LOGGED = [
    (event("EXECUTIVE_STARTED", "usecase", endpoint="tcp/127.0.0.1:7447", pid=4242),
     "usecase on tcp/127.0.0.1:7447 (pid 4242)"),
    (event("WORLD_SEEDED", "examples/usecase/problem.pddl", objects=3),
     "examples/usecase/problem.pddl: 3 objects"),
    (event("GOAL_ADDED", "goal 1", expression="(picture_taken lab)"), "goal 1: (picture_taken lab)"),
    (event("GOAL_UNREACHABLE", "goal 2", reason="no plan reaches it"),
     "goal 2: no plan reaches it"),
    (event("PLANNING", "goal planner", reason="goal 2 added; goal 3 added", goals=[1, 2, 3],
           blocked=[]),
     "for goals 1, 2, 3: goal 2 added; goal 3 added"),
    (event("PLAN_STORED", "plan 2", steps=5, engine="kairos", replaces=1),
     "plan 2: 5 steps by kairos, replaces plan 1"),
    (event("PLAN_START", "plan 3", steps=1, goals=[3, 4]), "plan 3: 1 step for goals 3, 4"),
    (event("START", "move_to(dock, lab)", plan=1, step=0, action="move_to",
           args=["dock", "lab"], undo=[["robot_at", ["dock"], True]]),
     "move_to(dock, lab) (plan 1, step 0); as it starts: (robot_at dock) no longer holds"),
    (event("END", "take_picture(lab)", plan=2, step=3, action="take_picture", args=["lab"],
           result={"place": "lab", "brightness": 179.7912, "image_stamp": 1_700_000_001.3912249}),
     "take_picture(lab) (plan 2, step 3); result: place lab, brightness 179.79, "
     "image_stamp {clock}"),
    (event("CANCEL", "move_to(dock, lab)", plan=1, step=0, action="move_to",
           args=["dock", "lab"], reason="not in the new plan"),
     "move_to(dock, lab) (plan 1, step 0): not in the new plan"),
    (event("REPLAN", "plan 2", reason="step move_to(dock, lab) failed: blocked"),
     "plan 2: step move_to(dock, lab) failed: blocked"),
    (event("TASK_REQUESTED", "task 1 move_to(dock, lab)", behavior="move_to",
           goal={"start": "dock", "target": "lab"}, duration=4.0),
     "task 1 move_to(dock, lab) (4 s)"),
    (event("TASK_STARTED", "task 2 move_to(dock, office)", behavior="move_to", attempt=3,
           providers={"base": "robot_base", "laser_scan": "lidar", "obstacle_scan": "lidar_filter"}),
     "task 2 move_to(dock, office) on lidar, lidar_filter, robot_base, attempt 3"),
    (event("TASK_RECONFIGURED", "task 6 move_to(lab, dock)", behavior="move_to",
           before={"base": "robot_base", "laser_scan": "lidar", "obstacle_scan": "lidar_filter"},
           after={"base": "robot_base", "camera": "cam", "obstacle_scan": "cam_to_lidar"}),
     "task 6 move_to(lab, dock): lidar, lidar_filter → cam, cam_to_lidar"),
    (event("TASK_CANCELLED", "task 1 move_to(dock, lab)", behavior="move_to",
           reason="the plan no longer needs it"),
     "task 1 move_to(dock, lab): the plan no longer needs it"),
    (event("CONFIGURATION", "nothing", stop=["robot_base", "lidar_filter", "lidar"], start=[],
           why="task 1 cancelled"),
     "task 1 cancelled: stop robot_base, lidar_filter, lidar; nothing runs"),
    (event("CONFIGURATION", "cam, cam_to_lidar, robot_base", stop=["lidar_filter", "lidar"],
           start=["cam", "cam_to_lidar"], why="lidar is permanently faulty"),
     "lidar is permanently faulty: stop lidar_filter, lidar; start cam, cam_to_lidar; "
     "running cam, cam_to_lidar, robot_base"),
    (event("REPAIR", "lidar", restart=True, unusable={}, tasks={"1": "restart"}),
     "lidar: restart; task 1: restart"),
    (event("REPAIR", "lidar", restart=False, tasks={"6": "restart"},
           unusable={"lidar": "is permanently faulty"}),
     "lidar: no restart; unusable: lidar (is permanently faulty); task 6: restart"),
    (event("REPAIR", "move_to", restart=True, attempt=2), "move_to: restart, attempt 2"),
    (event("TASK_RESTARTED", "task 2 move_to(dock, lab)", behavior="move_to", attempt=1,
           reason="configuration repaired"),
     "task 2 move_to(dock, lab), restart 1: configuration repaired"),
    (event("CONFIGURATION", "cam, cam_to_lidar, robot_base", stop=["lidar"], start=["cam"],
           resume=["cam_to_lidar"], why="lidar is permanently faulty"),
     "lidar is permanently faulty: stop lidar; resume cam_to_lidar; start cam; "
     "running cam, cam_to_lidar, robot_base"),
    (event("REPAIR", "task 2 move_to(dock, lab)", component="move_to", action="restart",
           behavior="move_to"),
     "task 2 move_to(dock, lab): restart move_to"),
    (event("FAULT", "lidar", count=3, permanent=True, reason="the diagnosis names it"),
     "lidar: fault 3, permanently faulty: the diagnosis names it"),
    (event("COMPONENT_READY", "lidar", pid=4250, exit_code=None, signal=None, reason="",
           stamp=1_700_000_000.123456),
     "lidar (pid 4250)"),
    (event("COMPONENT_EXITED", "lidar", pid=4250, exit_code=1, signal=None, reason="crashed"),
     "lidar (pid 4250) exited with code 1: crashed"),
    (event("COMPONENT_STOPPED", "lidar", pid=4250, exit_code=0, signal=None,
           reason="no task needs it"),
     "lidar (pid 4250): no task needs it"),
    (event("GOAL_RESULT_CANCELLED", "move_to", goal_id="82f78f1166e6", reason="cancelled"),
     "move_to, goal 82f78f1166e6"),
    (event("RULE_FIRED", "restart_lidar", action="restart lidar", faulty=["lidar"]),
     "restart_lidar: restart lidar (possibly faulty: lidar)"),
    (event("INTEGRITY_GOAL", "lidar_maintenance", goal=4, trigger="permanent_fault"),
     "lidar_maintenance: goal 4 (on permanent fault)"),
    (event("OBJECT_REMOVED", "hall", type="place", facts=["(photographable hall)"],
           source="user"),
     "hall (place) with 1 fact: (photographable hall)"),
    (event("STATE_SET", "(robot_at lab)", source="user"), "(robot_at lab) (by user)"),
    (event("STATE_SET", "(battery_low)", source="sensing", rule="low", topic="battery",
           field="charge.percent", value=14.2345),
     "(battery_low) (sensing rule low: charge.percent = 14.23)"),
    (event("GOAL_ADDED", "goal 5", expression="(robot_at dock)", keep=True),
     "goal 5: (robot_at dock), kept true"),
    (event("PARAMETER", "lidar", key="rate", value=5.0), "lidar: rate = 5"),
    (event("COMPONENT_RESET", "lidar", usable=["lidar", "lidar_filter"]),
     "lidar: usable again: lidar, lidar_filter"),
    (event("EXONERATION", "diagnosis", on=True), "diagnosis: exoneration on"),
    (event("HOST_JOINED", "front", components=["lidar", "lidar_filter"]),
     "host front joined: serves lidar, lidar_filter"),
    (event("HOST_LOST", "front", components=["lidar"]), "host front lost: ended lidar"),
]  # fmt: skip


@pytest.mark.parametrize(("logged", "reads"), LOGGED, ids=[e["kind"] for e, _ in LOGGED])
def test_each_kind_of_event_reads_as_a_sentence(logged: dict[str, Any], reads: str) -> None:
    clock = line({"stamp": 1_700_000_001.3912249})[:12]  # the local clock of that stamp
    assert describe(logged) == reads.format(clock=clock)


def test_no_event_shows_a_python_value() -> None:
    for logged, _ in LOGGED:
        text = describe(logged)
        assert not re.search(r"\[\[|\{'|\['|\bTrue\b|\bFalse\b|\bNone\b", text), text
    assert {e["kind"] for e, _ in LOGGED} >= {"START", "REPAIR", "CONFIGURATION", "END"}


def test_a_kind_nobody_knows_reads_as_its_subject_and_data() -> None:
    odd = event("SOMETHING_NEW", "lidar", values=[1, 2], deep={"a": [["x", True]]}, ratio=0.05962)
    assert describe(odd) == "lidar: values 1, 2, deep (a (x yes)), ratio 0.06"


def test_an_unexpected_shape_falls_back_to_the_generic_line() -> None:
    assert describe(event("FAULT", "lidar", reason="crashed")) == "lidar: reason crashed"


def test_a_log_line_keeps_its_columns_for_the_longest_kind() -> None:
    long, short = (line(event(k, "goal 1")) for k in ("GOAL_RESULT_SUCCEEDED", "GOAL_ADDED"))
    assert max(map(len, KINDS)) == WIDTH
    assert long.index("goal 1") == short.index("goal 1")
    assert re.match(r"\d\d:\d\d:\d\d\.250  GOAL_RESULT_SUCCEEDED  goal 1", long)
