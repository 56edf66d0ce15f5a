"""The four scenarios of the thesis (chapter 7) end to end: a real ``dura run`` with the
use-case components, clingo scheduling, a real bus and knowledge base. Tasks and
faults go in through the task executor's bus API (as ``dura task start`` and ``dura
component restart`` send them); each test reads the sequence of configurations and the
final states from the executive's event log.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import pytest

from executive.testing.harness import RobotProcess
from knowledge.records import Event
from tests.conftest import USECASE, wait_for

pytestmark = pytest.mark.slow

Start = Callable[..., RobotProcess]
LONG_MOVE = {"behaviors": {"move_to": {"params": {"duration": 8.0, "input_timeout": 2.0}}}}
NO_CAMERA = {
    "functionalities": {"cam": None, "cam_to_lidar": None},
    "behaviors": {"take_picture": None, "move_to": LONG_MOVE["behaviors"]["move_to"]},
    "tasks": {"take_picture": None},
}


def events_of(robot: RobotProcess, *kinds: str) -> list[Event]:
    return [e for e in robot.events() if e.kind in kinds]


def task_state(robot: RobotProcess, task_id: str) -> str:
    tasks = robot.request("task/list")["tasks"]
    return str(next(t["state"] for t in tasks if t["id"] == task_id))


def start_task(robot: RobotProcess, task: str, **goal: str) -> str:
    return str(robot.request("task/start", {"task": task, "goal": goal})["id"])


def started(robot: RobotProcess, task_id: str, times: int = 1) -> bool:
    subject = f"task {task_id} "
    return (
        len([e for e in events_of(robot, "TASK_STARTED") if e.subject.startswith(subject)]) >= times
    )


def restart_lidar_three_times(robot: RobotProcess, task_id: str) -> list[dict[str, Any]]:
    replies = []
    for fault in range(1, 4):
        assert wait_for(lambda: started(robot, task_id, fault), 30)  # noqa: B023
        replies.append(robot.request("component/restart", {"name": "lidar", "reason": "user"}))
    return replies


def configurations(robot: RobotProcess) -> list[tuple[list[str], list[str]]]:
    return [(e.data["start"], e.data["stop"]) for e in events_of(robot, "CONFIGURATION")]


def test_scenario_1_without_an_alternative_the_task_fails_after_the_third_fault(
    dura_robot: Start,
) -> None:
    robot = dura_robot(USECASE, changes=NO_CAMERA)
    task = start_task(robot, "move_to", start="dock", target="lab")
    replies = restart_lidar_three_times(robot, task)
    assert [(r["faults"], r["permanent"]) for r in replies] == [(1, False), (2, False), (3, True)]
    assert wait_for(lambda: task_state(robot, task) == "failed", 30)
    failed = events_of(robot, "TASK_FAILED")[-1]
    assert "no provider for capability 'obstacle_scan'" in failed.data["reason"]
    assert "lidar is permanently faulty" in failed.data["reason"]
    kinds = [e.kind for e in events_of(robot, "TASK_STARTED", "TASK_RESTARTED", "TASK_FAILED")]
    assert kinds == ["TASK_STARTED"] + ["TASK_RESTARTED", "TASK_STARTED"] * 2 + ["TASK_FAILED"]
    assert configurations(robot)[0] == (["lidar", "lidar_filter", "robot_base"], [])
    assert configurations(robot)[-1] == ([], ["robot_base", "lidar_filter", "lidar"])
    faults = {c.name: c for c in robot.status().faults}
    assert faults["lidar"].permanent_fault and faults["lidar"].fault_count == 3


def test_scenario_2_after_the_third_fault_move_to_switches_to_the_camera_and_succeeds(
    dura_robot: Start,
) -> None:
    robot = dura_robot(USECASE, changes=LONG_MOVE)
    task = start_task(robot, "move_to", start="dock", target="lab")
    restart_lidar_three_times(robot, task)
    assert wait_for(lambda: task_state(robot, task) == "succeeded", 60)
    switch = configurations(robot)[-2]
    assert switch == (["cam", "cam_to_lidar"], ["lidar_filter", "lidar"])
    last = [e for e in events_of(robot, "TASK_STARTED") if e.subject.startswith(f"task {task} ")]
    assert set(last[-1].data["providers"].values()) == {"cam", "cam_to_lidar", "robot_base"}


def test_scenario_3_two_moves_share_lidar_but_not_the_base_so_they_run_in_turn(
    dura_robot: Start,
) -> None:
    robot = dura_robot(USECASE)
    first = start_task(robot, "move_to", start="dock", target="lab")
    second = start_task(robot, "move_to", start="lab", target="office")
    assert wait_for(lambda: task_state(robot, second) == "succeeded", 60)
    assert task_state(robot, first) == "succeeded"
    trace = [
        (e.kind, e.subject.split()[1] if e.subject.startswith("task") else e.subject)
        for e in robot.events()
        if e.kind in ("TASK_STARTED", "TASK_SUCCEEDED", "COMPONENT_STOPPING")
    ]
    ran = [x for x in trace if x[0] != "COMPONENT_STOPPING"]
    assert ran == [
        ("TASK_STARTED", first),
        ("TASK_SUCCEEDED", first),
        ("TASK_STARTED", second),
        ("TASK_SUCCEEDED", second),
    ]
    between = trace[trace.index(("TASK_SUCCEEDED", first)) : trace.index(("TASK_STARTED", second))]
    assert ("COMPONENT_STOPPING", "lidar") not in between  # shared: it kept running
    assert ("COMPONENT_STOPPING", "lidar_filter") not in between


def test_scenario_4_move_and_pictures_share_the_camera_after_the_switch(
    dura_robot: Start,
) -> None:
    robot = dura_robot(USECASE, changes=LONG_MOVE)
    move = start_task(robot, "move_to", start="dock", target="lab")
    pictures = [start_task(robot, "take_picture", place="lab")]
    replies = restart_lidar_three_times(robot, move)
    assert replies[-1]["permanent"]
    pictures += [start_task(robot, "take_picture", place="lab") for _ in range(2)]
    assert wait_for(lambda: task_state(robot, move) == "succeeded", 60)
    assert wait_for(lambda: all(task_state(robot, p) == "succeeded" for p in pictures), 60)
    events = robot.events()
    switched = next(
        i for i, e in enumerate(events)
        if e.kind == "TASK_STARTED" and e.subject.startswith(f"task {move} ")
        and "cam_to_lidar" in e.data["providers"].values()
    )  # fmt: skip
    ended = next(
        i for i, e in enumerate(events)
        if e.kind == "TASK_SUCCEEDED" and e.subject.startswith(f"task {move} ")
    )  # fmt: skip
    stops = [e for e in events[switched:ended] if e.kind == "COMPONENT_STOPPING"]
    assert all(e.subject != "cam" for e in stops)  # cam runs while move_to needs it
