"""What the dashboard knows of a robot: how bus messages and replies change it, and the
views the page gets."""

from __future__ import annotations

import dataclasses
from typing import Any

import pytest

from executive.bus.payloads import ComponentState, DiagnosisInfo
from executive.bus.reports import ExecutorTask
from executive.bus.states import Lifecycle
from executive.dashboard.live import FAULTS, GOALS, PLAN, TASKS, LiveState, component_state, stale
from knowledge.records import ComponentRecord, Event
from knowledge.robot import load_robot
from tests.conftest import USECASE


@pytest.fixture
def state() -> LiveState:
    return LiveState(load_robot(USECASE))


def ready(name: str) -> ComponentState:
    return ComponentState(name, Lifecycle.READY, pid=7)


def event(number: int, kind: str, subject: str, **data: Any) -> Event:
    return Event(number, 0.0, kind, subject, data)


@pytest.mark.parametrize(
    ("lifecycle", "permanent", "faulty", "shown"),
    [
        (None, False, False, "stopped"),
        ({"state": "ready"}, False, False, "running"),
        ({"state": "paused"}, False, False, "paused"),
        ({"state": "starting"}, False, False, "starting"),
        ({"state": "exited", "exit_code": 0}, False, False, "stopped"),
        ({"state": "exited", "exit_code": 1}, False, False, "faulty"),
        ({"state": "exited", "exit_code": None, "signal": 9}, False, False, "faulty"),
        ({"state": "failed"}, False, False, "faulty"),
        ({"state": "ready"}, False, True, "faulty"),
        ({"state": "ready"}, True, True, "permanently faulty"),
    ],
)
def test_a_component_is_drawn_in_the_state_a_person_cares_about(
    lifecycle: dict[str, Any] | None, permanent: bool, faulty: bool, shown: str
) -> None:
    reported = (
        None if lifecycle is None else ComponentState.from_payload({"component": "c", **lifecycle})
    )
    assert component_state(reported, permanent=permanent, faulty=faulty) == shown


def test_each_event_asks_again_only_for_what_it_changed() -> None:
    assert stale("GOAL_ADDED") == {GOALS, PLAN}
    assert stale("DISPATCH") == {PLAN}
    assert stale("CONFIGURATION") == {TASKS}
    assert stale("FAULT") == {FAULTS, TASKS}
    assert stale("COMPONENT_READY") == set()
    assert stale("EXECUTIVE_STARTED") >= {GOALS, PLAN, TASKS, FAULTS}


def test_a_diagnosed_component_is_faulty_until_the_all_clear(state: LiveState) -> None:
    state.set_lifecycle(ready("lidar"))
    state.set_diagnosis(DiagnosisInfo("DIAGNOSED", (("lidar",),),
                                      failed=({"type": "timeout", "resource": ["scan"]},)))  # fmt: skip
    drawn = state.graph_state()
    assert drawn.states["lidar"] == "faulty" and drawn.diagnosed == {"lidar"}
    assert drawn.failed_topics == {"scan"}
    state.set_diagnosis(DiagnosisInfo("OK"))
    assert state.graph_state().states["lidar"] == "running"


def test_a_component_stays_faulty_from_its_fault_until_it_is_ready_again(
    state: LiveState,
) -> None:
    state.set_lifecycle(ready("lidar"))
    state.add_event(event(1, "FAULT", "lidar", count=1))
    assert state.graph_state().states["lidar"] == "faulty"
    state.set_lifecycle(dataclasses.replace(ready("lidar"), state=Lifecycle.STOPPED))
    assert state.graph_state().states["lidar"] == "faulty"
    state.set_lifecycle(ready("lidar"))
    assert state.graph_state().states["lidar"] == "running"


def test_permanent_faults_and_counters_come_from_the_fault_records(state: LiveState) -> None:
    state.set_faults(
        [ComponentRecord("lidar", 10.0, fault_count=3, permanent_fault=True, reason="r")],
        ["lidar", "lidar_filter"],
    )
    drawn = state.graph_state()
    assert drawn.states["lidar"] == drawn.states["lidar_filter"] == "permanently faulty"
    assert drawn.faults == {"lidar": (3, 3)}


def test_active_tasks_give_the_configuration_drawn_over_the_graph(state: LiveState) -> None:
    state.set_tasks([
        ExecutorTask("1", "move_to(dock, lab)", "move_to", {}, "running",
                     {"laser_scan": "lidar", "obstacle_scan": "lidar_filter", "base": "robot_base"},
                     ("lidar", "lidar_filter", "robot_base"), 4.0),
        ExecutorTask("2", "take_picture(lab)", "take_picture", {}, "succeeded",
                     {"camera": "cam"}, ("cam",), 2.0),
    ])  # fmt: skip
    drawn = state.graph_state()
    assert drawn.used == {("laser_scan", "lidar"), ("obstacle_scan", "lidar_filter"),
                          ("base", "robot_base")}  # fmt: skip
    assert drawn.tasks["move_to"] == ("task 1 move_to(dock, lab)",)
    assert "cam" not in drawn.tasks
    view = state.view("components")
    assert [c["id"] for c in view["configurations"]] == ["1"]


def test_events_are_kept_once_in_the_logs_order(state: LiveState) -> None:
    assert state.add_event(event(5, "DISPATCH", "s"))
    assert not state.add_event(event(5, "DISPATCH", "s"))
    state.set_events([event(n, "GOAL_ADDED", "g") for n in (3, 4, 5)])
    assert [e["id"] for e in state.view("events")["events"]] == [3, 4, 5]
    assert [e.id for e in state.plan_events] == [5]


def test_observations_keep_the_last_minutes_of_their_values(state: LiveState) -> None:
    for t in range(0, 400, 50):
        state.add_observation(
            {"observer": "lidar/0", "type": "frequency", "resource": ["scan"], "observation": 1,
             "observation_msg": "ok", "values": {"frequency": 10.0 + t, "flag": True},
             "stamp": float(t)}
        )  # fmt: skip
    (track,) = state.view("observations")["observations"]
    assert track["observer"] == "lidar/0" and track["values"] == {"frequency": 360.0}
    assert [t for t, _ in track["history"]] == [50.0, 100.0, 150.0, 200.0, 250.0, 300.0, 350.0]


def test_without_a_plan_the_plan_view_says_so(state: LiveState) -> None:
    assert state.view("plan")["title"] == "no plan yet"


def test_an_event_reaches_the_page_with_its_readable_line(state: LiveState) -> None:
    state.add_event(event(9, "FAULT", "lidar", count=1, permanent=False, reason="crashed"))
    assert state.view("events")["events"][-1]["text"] == "lidar: fault 1: crashed"


def test_a_failed_component_shows_what_it_wrote_last(state: LiveState) -> None:
    output = ('  File "barista.py", line 7, in on_water', "TypeError: 'Message' object ...")
    state.set_lifecycle(
        ComponentState(
            "lidar", Lifecycle.FAILED, exit_code=1, reason="exited ... (dura component logs lidar)",
            output=output,
        )
    )  # fmt: skip
    lidar = next(c for c in state.components_view()["components"] if c["name"] == "lidar")
    assert lidar["reason"] == "exited ... (dura component logs lidar)"
    assert lidar["output"] == list(output)
