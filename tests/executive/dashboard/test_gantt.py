"""The plan as a Gantt chart: what each row, mark and tooltip of the picture says."""

from __future__ import annotations

import dataclasses
import re
from typing import Any

import pytest

from executive.bus.reports import ExecutionStatus, ExecutorTask
from executive.bus.schema import read
from executive.dashboard import gantt
from executive.planning.partial_order import PartialOrderPlan, Precedence, Step, Timepoint
from knowledge.records import Event, Plan, PlanState
from tests.executive.dashboard.pictures import SVG, groups, parse, texts, tooltip

PLAN: Plan = read(Plan, {
    "id": 2, "state": "executing", "engine": "kairos", "goal_ids": [1, 3], "created": 1000.0,
    "steps": [
        {"index": 0, "action": "move_to", "args": ["dock", "lab"], "start": 0.0, "duration": 5.0},
        {"index": 1, "action": "take_picture", "args": ["lab"], "start": 5.0, "duration": 2.0},
        {"index": 2, "action": "move_to", "args": ["lab", "dock"], "start": 7.0, "duration": 5.0},
    ],
}, "plan")  # fmt: skip
EXECUTION: ExecutionStatus = read(ExecutionStatus, {"plan": 2, "steps": [
    {"index": 0, "step": "move_to(dock, lab)", "state": "ended"},
    {"index": 1, "step": "take_picture(lab)", "state": "running"},
    {"index": 2, "step": "move_to(lab, dock)", "state": "pending"}]}, "execution")  # fmt: skip
EVENTS: list[Event] = read(list[Event], [
    {"id": 1, "stamp": 980.0, "kind": "PLAN_START", "subject": "plan 1", "data": {}},
    {"id": 2, "stamp": 990.0, "kind": "REPLAN", "subject": "plan 1",
     "data": {"reason": "move_to(dock, lab) failed"}},
    {"id": 3, "stamp": 1001.0, "kind": "PLAN_START", "subject": "plan 2", "data": {}},
    {"id": 4, "stamp": 1001.1, "kind": "DISPATCH", "subject": "move_to(dock, lab)",
     "data": {"plan": 2, "step": 0}},
    {"id": 5, "stamp": 1007.0, "kind": "END", "subject": "move_to(dock, lab)",
     "data": {"plan": 2, "step": 0}},
    {"id": 6, "stamp": 1007.1, "kind": "DISPATCH", "subject": "take_picture(lab)",
     "data": {"plan": 2, "step": 1}},
], "events")  # fmt: skip
TASKS = [
    ExecutorTask("7", "take_picture(lab)", "take_picture", {}, "failed", {"camera": "cam"},
                 ("cam",), 2.0),
    ExecutorTask("9", "take_picture(lab)", "take_picture", {}, "running", {"camera": "cam"},
                 ("cam",), 2.0),
]  # fmt: skip


def live() -> gantt.Gantt:
    return gantt.live_gantt(PLAN, EXECUTION, EVENTS, TASKS, now=1008.0)


def test_a_live_chart_has_a_row_per_step_with_its_state() -> None:
    chart = live()
    assert [(s.label, s.state) for s in chart.steps] == [
        ("move_to(dock, lab)", "done"),
        ("take_picture(lab)", "running"),
        ("move_to(lab, dock)", "pending"),
    ]
    assert chart.title == "plan 2: executing, by kairos, for goals 1, 3"


def test_times_count_from_the_current_plans_start_and_steps_ran_from_dispatch_to_end() -> None:
    chart = live()
    assert chart.now == 7.0
    assert chart.steps[0].ran == pytest.approx((0.1, 6.0))
    assert chart.steps[1].ran is not None and chart.steps[1].ran[1] is None  # running
    assert chart.steps[2].ran is None


def test_earlier_plans_and_replans_are_marked_on_the_time_axis() -> None:
    marks = live().marks
    assert [(m.at, m.kind) for m in marks] == [(-21.0, "plan"), (-11.0, "replan"), (0.0, "plan")]
    assert marks[1].text == "replan: move_to(dock, lab) failed"


def test_a_step_shows_its_newest_task_and_configuration_on_hover() -> None:
    step = live().steps[1]
    assert "task 9: take_picture running" in step.details
    assert "configuration: camera → cam" in step.details
    root = parse(gantt.render(live()))
    rows = groups(root, "step")
    assert [r.get("data-state") for r in rows] == ["done", "running", "pending"]
    assert "configuration: camera → cam" in tooltip(rows[1])


def test_the_picture_draws_the_marks_the_now_line_and_a_legend() -> None:
    root = parse(gantt.render(live()))
    assert [m.get("data-kind") for m in groups(root, "mark")] == ["plan", "replan", "plan"]
    assert any(line.get("class") == "now" for line in root.iter("{http://www.w3.org/2000/svg}line"))
    drawn = texts(root)
    assert "plan 2: executing, by kairos, for goals 1, 3" in drawn
    assert {"pending", "running", "done", "failed"} <= set(drawn)


def test_an_offline_plan_is_drawn_with_its_precedences_on_hover() -> None:
    plan = PartialOrderPlan(
        (
            Step(0, "drive", ("dock", "store"), (), 0.0, 5.0),
            Step(1, "pick", ("parcel", "store"), (), 5.0, 3.0,
                 after=(Precedence(0, Timepoint.END),)),
        )
    )  # fmt: skip
    root = parse(gantt.render(gantt.offline_gantt(plan, "parcel.pddl: 2 steps")))
    rows = groups(root, "step")
    assert [r.get("data-label") for r in rows] == ["drive(dock, store)", "pick(parcel, store)"]
    assert "after step 0" in tooltip(rows[1])
    assert not groups(root, "mark")


def test_text_from_the_robot_is_escaped_in_the_picture() -> None:
    step = read(
        Plan,
        {
            "id": 2,
            "state": "executing",
            "steps": [
                {"index": 0, "action": "a<b>&", "args": ['"x"'], "start": 0.0, "duration": None}
            ],
        },
        "plan",
    )
    plan = dataclasses.replace(PLAN, steps=step.steps)  # fmt: skip
    root = parse(gantt.render(gantt.live_gantt(plan, ExecutionStatus(), [], [], now=1000.0)))
    assert groups(root, "step")[0].get("data-label") == 'a<b>&("x")'


def test_ticks_are_round_numbers_across_the_span() -> None:
    assert gantt.ticks(0, 10) == [0, 2, 4, 6, 8, 10]
    assert gantt.ticks(-21, 12)[:2] == [-20, -15]


def test_a_step_adopted_from_the_plan_before_ran_since_that_plans_dispatch() -> None:
    events: list[Any] = read(list[Event], [
        {"id": 1, "stamp": 990.0, "kind": "DISPATCH", "subject": "move_to(dock, lab)",
         "data": {"plan": 1, "step": 0}},
        {"id": 2, "stamp": 1000.0, "kind": "PLAN_START", "subject": "plan 2", "data": {}},
    ], "events")  # fmt: skip
    execution = read(ExecutionStatus, {"plan": 2, "steps": [
        {"index": 0, "step": "move_to(dock, lab)", "state": "running"}]}, "execution")  # fmt: skip
    plan = dataclasses.replace(PLAN, steps=PLAN.steps[:1])
    (step,) = gantt.live_gantt(plan, execution, events, [], now=1004.0).steps
    assert step.ran == (-10.0, None)


def test_a_finished_plan_is_drawn_on_its_own_span_and_one_goal_is_said_so() -> None:
    done = dataclasses.replace(PLAN, state=PlanState.SUCCEEDED, goal_ids=(4,))
    chart = gantt.live_gantt(done, ExecutionStatus(), EVENTS, TASKS, now=1100.0)
    assert chart.now is None  # 100 s later: no axis that grows with the clock
    assert chart.title == "plan 2: succeeded, by kairos, for goal 4"
    drawn = texts(parse(gantt.render(chart)))
    ticks = [float(t.removesuffix(" s")) for t in drawn if re.fullmatch(r"-?\d+ s", t)]
    assert max(ticks) < 20 and "now" not in drawn  # its steps end at 12 s


def test_the_page_s_chart_leaves_the_title_to_the_page() -> None:
    assert live().title not in texts(parse(gantt.render(live(), titled=False)))
    assert live().title in texts(parse(gantt.render(live())))


def test_a_fleets_plan_is_drawn_by_robot_each_robots_steps_together() -> None:
    plan: Plan = read(Plan, {
        "id": 4, "state": "executing", "engine": "kairos", "goal_ids": [1, 2], "created": 1000.0,
        "steps": [
            {"index": 0, "action": "drive", "args": ["r2", "dock2", "store"], "start": 0.0,
             "duration": 5.0},
            {"index": 1, "action": "drive", "args": ["r1", "dock1", "store"], "start": 0.0,
             "duration": 5.0},
            {"index": 2, "action": "pick", "args": ["r2", "parcel2", "store"], "start": 5.0,
             "duration": 3.0},
            {"index": 3, "action": "pick", "args": ["r1", "parcel1", "store"], "start": 5.0,
             "duration": 3.0},
        ],
    }, "plan")  # fmt: skip
    chart = gantt.live_gantt(plan, ExecutionStatus(), [], [], now=1001.0,
                             robots=["r2", "r1", "r2", "r1"])  # fmt: skip
    assert [(s.robot, s.index) for s in chart.steps] == [("r1", 1), ("r1", 3), ("r2", 0), ("r2", 2)]
    root = parse(gantt.render(chart))
    rows = groups(root, "step")
    assert [g.get("data-robot") for g in rows] == ["r1", "r1", "r2", "r2"]
    # a row per robot: its name, and each of its steps a bar in that row, labelled in it
    assert [t.text for t in root.iter(f"{SVG}text") if t.get("class") == "robot"] == ["r1", "r2"]
    assert "drive(r1, dock1, store)" in texts(rows[0])
    heights = [float(next(g.iter(f"{SVG}rect")).get("y") or 0) for g in rows]
    assert heights[0] == heights[1] < heights[2] == heights[3]
    assert "robot r2" in tooltip(rows[2])
    # a robot's own plan has no robot column
    assert all(g.get("data-robot") is None for g in groups(parse(gantt.render(live())), "step"))


def test_a_fleets_step_no_robot_carries_out_has_a_row_of_its_own() -> None:
    plan = dataclasses.replace(PLAN, steps=PLAN.steps[:2])
    chart = gantt.live_gantt(plan, ExecutionStatus(), [], [], now=1001.0, robots=["r1", ""])
    assert [(label, [s.index for s in steps]) for label, steps in gantt.rows(chart)] == [
        ("r1", [0]),
        ("-", [1]),
    ]
    own = gantt.rows(live())  # a robot's own plan: a row per step
    assert [label for label, _ in own] == [f"{s.index}  {s.label}" for s in live().steps]
