"""The task executor with real component processes, bus and knowledge base: status
queries from its snapshot, why a task ended as code reads it, and what keeps running
between tasks (lingering, warm spares, plan steps to come, a failed step's replan)."""

from __future__ import annotations

import dataclasses
from pathlib import Path
from typing import Any

import pytest

from executive.bus.api.tasks import SCHEDULE_SHOW, TASK_LIST, TASK_STOP, TaskId
from executive.bus.clock import Clock
from executive.bus.states import Lifecycle
from executive.tasks.executor import TaskExecutor
from executive.tasks.task import TaskEnd, TaskHandle, TaskPhase
from knowledge.description import RobotDescription
from knowledge.records import Event
from tests.conftest import wait_for
from tests.executive.runtime.rig import USECASE_ROBOT, Rig, robot, usecase
from tests.executive.tasks.executor_rig import executor, slow_camera_robot

pytestmark = pytest.mark.slow


def test_status_queries_answer_from_the_snapshot_while_a_component_starts_slowly(
    endpoint: str, tmp_path: Path
) -> None:
    with executor(slow_camera_robot(delay=4.0), endpoint, tmp_path) as (tasks, r):
        first = tasks.start_task("take_picture", {"place": "lab"})
        assert wait_for(lambda: r.launcher.state("slow_cam").state is Lifecycle.STARTING, 10)
        # the worker is inside the camera's start now; a task asked for meanwhile is
        # listed at once, before the worker can take it up
        second = tasks.start_task("take_picture", {"place": "office"})
        queries = {
            "tasks()": tasks.tasks,
            "schedule()": tasks.schedule,
            "task/list": lambda: TASK_LIST.call(r.bus),
            "schedule/show": lambda: SCHEDULE_SHOW.call(r.bus),
        }
        for query in queries.values():
            query()
        # every query answered while the camera was still starting: none waited for it
        assert r.launcher.state("slow_cam").state is Lifecycle.STARTING
        listed = {t.id: t.state for t in TASK_LIST.call(r.bus).tasks}
        assert listed == {first.id: "starting", second.id: "waiting"}
        assert SCHEDULE_SHOW.call(r.bus).running == ["slow_cam"]
        assert first.wait(30) and first.phase is TaskPhase.SUCCEEDED, first.reason
        assert first.end is TaskEnd.SUCCEEDED
        assert second.wait(30) and second.phase is TaskPhase.SUCCEEDED, second.reason
        assert wait_for(lambda: [t.state for t in tasks.tasks()] == ["succeeded"] * 2)


def test_a_task_ended_by_its_requester_or_by_a_user_says_who_ended_it(
    endpoint: str, tmp_path: Path
) -> None:
    with executor(slow_camera_robot(delay=0.5, picture=5.0), endpoint, tmp_path) as (tasks, r):
        mine = tasks.start_task("take_picture", {"place": "lab"})
        theirs = tasks.start_task("take_picture", {"place": "office"})  # waits for mine
        mine.cancel("no longer needed")
        stopped = TASK_STOP.call(r.bus, TaskId(theirs.id)).task
        assert (stopped.state, stopped.ended_by) == ("cancelled", "user")
        assert mine.wait(30) and theirs.wait(30)
        assert (mine.phase, mine.end, mine.reason) == (
            TaskPhase.CANCELLED,
            TaskEnd.REQUESTER,
            "no longer needed",
        )
        assert (theirs.phase, theirs.end, theirs.reason) == (
            TaskPhase.CANCELLED,
            TaskEnd.USER,
            "stopped by the user",
        )


def test_a_functionality_lingers_after_its_last_task_then_stops(
    endpoint: str, tmp_path: Path
) -> None:
    robot = slow_camera_robot(delay=0.1, picture=0.5)
    with executor(robot, endpoint, tmp_path, linger=3.0) as (tasks, r):
        first = tasks.start_task("take_picture", {"place": "lab"})
        assert first.wait(30) and first.phase is TaskPhase.SUCCEEDED, first.reason
        assert r.launcher.state("slow_cam").state is Lifecycle.READY  # it lingers
        second = tasks.start_task("take_picture", {"place": "office"})
        assert second.wait(30) and second.phase is TaskPhase.SUCCEEDED, second.reason
        assert wait_for(lambda: r.launcher.state("slow_cam").state is Lifecycle.STOPPED, 30)
        starts = [e for e in r.kb.events(kind="COMPONENT_STARTING") if e.subject == "slow_cam"]
        assert len(starts) == 1  # the second picture found it running
        last = r.kb.events(kind="CONFIGURATION")[-1]
        assert last.data["stop"] == ["slow_cam"] and "linger" in last.data["why"]


def failover_robot(*spares: str) -> RobotDescription:
    """move_to (30 s) on lidar or the camera; ``spares`` have ``standby: true``."""
    functionalities = [
        usecase(n, standby=n in spares)
        for n in ("lidar", "lidar_filter", "robot_base", "cam", "cam_to_lidar")
    ]
    move_to = usecase("move_to", params={"duration": 30.0, "input_timeout": 5.0})
    tasks = {"move_to": USECASE_ROBOT.tasks["move_to"]}
    return dataclasses.replace(robot(*functionalities, move_to), tasks=tasks)


def states_of(r: Rig) -> list[tuple[str, str]]:
    return [(e.kind, e.subject) for e in r.kb.events() if e.kind.startswith("COMPONENT_")]


def test_a_failover_starts_the_new_providers_at_once_before_the_old_ones_stop(
    endpoint: str, tmp_path: Path
) -> None:
    with executor(failover_robot(), endpoint, tmp_path) as (tasks, r):
        move = tasks.start_task("move_to", {"target": "lab"})
        assert wait_for(lambda: move.phase is TaskPhase.RUNNING, 30)
        tasks.fault("lidar", "test", permanent=True)
        assert wait_for(lambda: move.providers.get("obstacle_scan") == "cam_to_lidar", 30)
        assert wait_for(lambda: move.phase is TaskPhase.RUNNING, 30)
        seen = states_of(r)
        at = seen.index
        both_started = max(
            at(("COMPONENT_STARTING", "cam")), at(("COMPONENT_STARTING", "cam_to_lidar"))
        )
        first_ready = min(at(("COMPONENT_READY", "cam")), at(("COMPONENT_READY", "cam_to_lidar")))
        assert both_started < first_ready  # at once, not one after the other
        ready = max(at(("COMPONENT_READY", "cam")), at(("COMPONENT_READY", "cam_to_lidar")))
        assert ready < at(("COMPONENT_STOPPING", "lidar_filter"))  # make before break


def test_a_warm_spare_waits_paused_and_a_failover_resumes_it_without_a_start(
    endpoint: str, tmp_path: Path
) -> None:
    with executor(failover_robot("cam_to_lidar"), endpoint, tmp_path) as (tasks, r):
        assert wait_for(lambda: r.launcher.state("cam_to_lidar").state is Lifecycle.PAUSED, 30)
        assert wait_for(lambda: r.launcher.state("cam").state is Lifecycle.PAUSED, 30)
        move = tasks.start_task("move_to", {"target": "lab"})
        assert wait_for(lambda: move.phase is TaskPhase.RUNNING, 30)
        assert r.launcher.state("cam_to_lidar").state is Lifecycle.PAUSED  # still a spare
        tasks.fault("lidar", "test", permanent=True)
        assert wait_for(lambda: move.providers.get("obstacle_scan") == "cam_to_lidar", 30)
        assert wait_for(lambda: r.launcher.state("cam_to_lidar").state is Lifecycle.READY, 30)
        starts = [s for k, s in states_of(r) if k == "COMPONENT_STARTING"]
        assert starts.count("cam_to_lidar") == 1 and starts.count("cam") == 1  # resumed
        seen = states_of(r)
        resumed = len(seen) - 1 - seen[::-1].index(("COMPONENT_READY", "cam_to_lidar"))
        assert resumed < seen.index(("COMPONENT_STOPPING", "lidar_filter"))


def test_the_next_steps_behavior_starts_ahead_and_keeps_running_between_its_steps(
    endpoint: str, tmp_path: Path
) -> None:
    robot = slow_camera_robot(delay=0.1, picture=0.5)
    with executor(robot, endpoint, tmp_path) as (tasks, r):
        tasks.expect(["take_picture", "take_picture"])  # a plan's steps to come
        # started before its task, with no task: ready when the first step comes
        assert wait_for(lambda: r.launcher.state("take_picture").state is Lifecycle.READY, 30)
        pid = r.launcher.state("take_picture").pid
        first = tasks.start_task("take_picture", {"place": "lab"})
        tasks.expect(["take_picture"])  # the first step runs, one is to come
        assert first.wait(30) and first.phase is TaskPhase.SUCCEEDED, first.reason
        assert r.launcher.state("take_picture").pid == pid  # kept for the step to come
        second = tasks.start_task("take_picture", {"place": "office"})
        tasks.expect([])  # the last step runs
        assert second.wait(30) and second.phase is TaskPhase.SUCCEEDED, second.reason
        assert wait_for(lambda: r.launcher.state("take_picture").state is Lifecycle.STOPPED, 30)
        starts = [e for e in r.kb.events(kind="COMPONENT_STARTING")
                  if e.subject == "take_picture"]  # fmt: skip
        assert len(starts) == 1  # one process for both steps
        assert [e.data["attempt"] for e in r.kb.events(kind="TASK_STARTED")] == [1, 1]


def test_a_behavior_started_ahead_stops_when_no_step_to_come_needs_it(
    endpoint: str, tmp_path: Path
) -> None:
    robot = slow_camera_robot(delay=0.1, picture=0.5)
    with executor(robot, endpoint, tmp_path) as (tasks, r):
        tasks.expect(["take_picture"])
        assert wait_for(lambda: r.launcher.state("take_picture").state is Lifecycle.READY, 30)
        tasks.expect([])  # the plan was dropped
        assert wait_for(lambda: r.launcher.state("take_picture").state is Lifecycle.STOPPED, 30)
        assert r.kb.events(kind="TASK_STARTED") == []


SLOW = Clock(0.1)  # robot time at a tenth: the failed step's grace outlasts any new step
BASE = ("lidar", "lidar_filter", "robot_base")  # move_to's configuration


def all_stopped(r: Rig, names: tuple[str, ...]) -> bool:
    return all(r.launcher.state(n).state is Lifecycle.STOPPED for n in names)


def crash_when_running(r: Rig, move: TaskHandle) -> None:
    """Crash the behavior of a move task once it runs; wait until the task failed."""
    assert wait_for(lambda: move.phase is TaskPhase.RUNNING, 30)
    r.launcher.inject_fault("move_to", "crash")
    assert move.wait(30) and move.end is TaskEnd.BEHAVIOR_FAILED, move.reason


def base_stops(r: Rig) -> list[Event]:
    """The CONFIGURATION events that stop any of move_to's functionalities."""
    return [e for e in r.kb.events(kind="CONFIGURATION") if set(BASE) & set(e.data["stop"])]


def plan_step(tasks: TaskExecutor, r: Rig, behavior: str, goal: dict[str, Any]) -> TaskHandle:
    """The first step of a new plan (stored), running ``behavior``."""
    return tasks.start_task(behavior, goal, plan_id=r.kb.store_plan([]).id, step=0)


def replan_robot() -> RobotDescription:
    """The failover robot whose move_to fails at its first crash, and take_picture
    (30 s, on the camera)."""
    move_to = usecase("move_to", max_restarts=0, params={"duration": 30.0, "input_timeout": 5.0})
    described = failover_robot()
    return dataclasses.replace(
        described,
        behaviors={**described.behaviors, "move_to": move_to,
                   "take_picture": usecase("take_picture", params={"duration": 30.0})},
    )  # fmt: skip


@pytest.mark.parametrize("sequential", [False, True], ids=["parallel", "sequential"])
def test_the_new_plans_step_takes_over_a_failed_steps_functionalities_without_a_start(
    endpoint: str, tmp_path: Path, sequential: bool
) -> None:
    with executor(replan_robot(), endpoint, tmp_path, sequential=sequential, clock=SLOW) as (
        tasks,
        r,
    ):
        failed = plan_step(tasks, r, "move_to", {"target": "lab"})
        crash_when_running(r, failed)
        # the planner plans again, and the new plan's first step runs the same behavior
        again = plan_step(tasks, r, "move_to", {"target": "lab"})
        assert wait_for(lambda: again.phase is TaskPhase.RUNNING, 30), again.reason
        assert again.providers == failed.providers
        starts = [s for k, s in states_of(r) if k == "COMPONENT_STARTING"]
        assert [starts.count(n) for n in BASE] == [1, 1, 1]  # kept for the new plan
        assert starts.count("move_to") == 2  # the crashed behavior was not kept
        stops = [s for k, s in states_of(r) if k == "COMPONENT_STOPPING"]
        assert not set(BASE) & set(stops)


def test_a_failed_steps_functionalities_no_new_step_takes_over_stop_when_the_grace_ends(
    endpoint: str, tmp_path: Path
) -> None:
    with executor(replan_robot(), endpoint, tmp_path, clock=Clock(2.0)) as (tasks, r):
        failed = plan_step(tasks, r, "move_to", {"target": "lab"})
        crash_when_running(r, failed)
        picture = plan_step(tasks, r, "take_picture", {"place": "lab"})  # needs none of them
        assert wait_for(lambda: picture.phase is TaskPhase.RUNNING, 30), picture.reason
        assert wait_for(lambda: all_stopped(r, BASE), 30)
        assert picture.phase is TaskPhase.RUNNING  # no task ended meanwhile: the grace did
        stops = base_stops(r)
        assert len(stops) == 1 and set(stops[0].data["stop"]) == set(BASE)
        assert "linger" in stops[0].data["why"]  # not at the failure: when the grace ended


def test_a_behavior_marked_faulty_stops_at_once_while_its_steps_functionalities_wait(
    endpoint: str, tmp_path: Path
) -> None:
    with executor(replan_robot(), endpoint, tmp_path, clock=Clock(2.0)) as (tasks, r):
        failed = plan_step(tasks, r, "move_to", {"target": "lab"})
        assert wait_for(lambda: failed.phase is TaskPhase.RUNNING, 30)
        tasks.fault("move_to", "diagnosed faulty", permanent=True)
        assert failed.wait(30) and failed.end is TaskEnd.BEHAVIOR_FAULTY, failed.reason
        assert r.launcher.state("move_to").state is Lifecycle.STOPPED  # not kept
        assert wait_for(lambda: all_stopped(r, BASE), 30)
        seen = states_of(r)
        assert seen.index(("COMPONENT_STOPPED", "move_to")) < min(
            seen.index(("COMPONENT_STOPPING", n)) for n in BASE
        )
        stops = base_stops(r)
        assert len(stops) == 1 and "linger" in stops[0].data["why"]


def test_a_failed_task_of_no_plan_stops_its_functionalities_at_once(
    endpoint: str, tmp_path: Path
) -> None:
    with executor(replan_robot(), endpoint, tmp_path) as (tasks, r):
        failed = tasks.start_task("move_to", {"target": "lab"})  # a user's task: no replan
        crash_when_running(r, failed)
        assert wait_for(lambda: all_stopped(r, BASE), 30)
        stops = base_stops(r)
        assert len(stops) == 1 and stops[0].data["why"] == f"task {failed.id} failed"


def test_a_goal_the_world_makes_impossible_fails_its_task_without_a_fault_or_restart(
    endpoint: str, tmp_path: Path
) -> None:
    with executor(USECASE_ROBOT, endpoint, tmp_path) as (tasks, r):
        move = tasks.start_task("move_to", {})  # move_to raises GoalFailed: no 'target'
        assert move.wait(60), move.reason
        assert (move.phase, move.end, move.reason) == (
            TaskPhase.FAILED,
            TaskEnd.GOAL_FAILED,
            "the goal has no 'target'",
        )
        assert r.kb.events(kind="FAULT") == []
        assert r.kb.events(kind="TASK_RESTARTED") == []
        assert r.kb.component("move_to").fault_count == 0
