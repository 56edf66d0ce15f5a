"""The task executor's decisions without processes, bus or knowledge base: tasks as
views, faults and ratings as plain data, the time passed in."""

from __future__ import annotations

import dataclasses
from typing import Any

import pytest

from executive.tasks.configuration import SystemConfiguration, Transition
from executive.tasks.decisions import Decision, decide, keep_running
from executive.tasks.task import TaskPhase, TaskView
from knowledge.description import RobotDescription
from tests.executive.tasks.scheduling_cases import usecase_robot

NOW = 1000.0
LIDAR = {"base": "robot_base", "laser_scan": "lidar", "obstacle_scan": "lidar_filter"}
CAM = {"base": "robot_base", "camera": "cam", "obstacle_scan": "cam_to_lidar"}


def task(task_id: str, behavior: str = "move_to", **fields: Any) -> TaskView:
    """A task asked for just now, 10 s long, with changed fields."""
    fields.setdefault("earliest", NOW)
    return TaskView(task_id, behavior, fields.pop("duration", 10.0), **fields)


def running(task_id: str, providers: dict[str, str], **fields: Any) -> TaskView:
    """A task whose behavior runs on ``providers`` since ``began`` (default: now)."""
    fields.setdefault("began", NOW)
    return task(task_id, phase=TaskPhase.RUNNING, providers=providers, **fields)


def on(*tasks: TaskView) -> SystemConfiguration:
    """The configuration these tasks hold."""
    return SystemConfiguration({t.id: dict(t.providers) for t in tasks})


def decision(
    *tasks: TaskView,
    running: SystemConfiguration | None = None,
    robot: RobotDescription | None = None,
    faulty: frozenset[str] = frozenset(),
    ratings: dict[str, float] | None = None,
) -> Decision:
    return decide(
        tasks,
        running if running is not None else on(*(t for t in tasks if t.phase.holds)),
        robot=robot or usecase_robot(),
        faulty=faulty,
        ratings=ratings or {},
        now=NOW,
    )


def without(*names: str) -> RobotDescription:
    robot = usecase_robot()
    kept = {n: f for n, f in robot.functionalities.items() if n not in names}
    return dataclasses.replace(robot, functionalities=kept)


def test_a_task_on_an_idle_robot_starts_now_and_its_configuration_comes_up_in_order() -> None:
    d = decision(task("1"))
    assert d.start_now == {"1": LIDAR}
    assert not d.start_later and not d.cancelled and not d.behind_running
    assert d.configuration == SystemConfiguration({"1": LIDAR})
    assert d.transition == Transition(start=("lidar", "lidar_filter", "robot_base"))
    assert d.wake is None


def test_a_task_with_a_later_earliest_start_starts_later_and_nothing_starts_yet() -> None:
    d = decision(task("1", earliest=NOW + 5.0))
    assert d.start_later == {"1": pytest.approx(NOW + 5.0)}
    assert d.wake == pytest.approx(NOW + 5.0)
    assert not d.start_now
    assert d.transition.empty and d.configuration == SystemConfiguration()


def test_a_second_move_waits_behind_the_running_one_without_a_time() -> None:
    first = running("1", LIDAR)
    d = decision(first, task("2"))
    assert d.behind_running == {"2"}
    assert d.behind == {"2": ("1",)}  # what the schedule view draws it after
    assert not d.start_now and not d.start_later and d.wake is None
    assert d.transition.empty  # the first keeps its configuration
    assert d.configuration == on(first)


def test_a_running_task_is_scheduled_for_what_remains_of_it() -> None:
    d = decision(running("1", LIDAR, began=NOW - 8.0))
    assert d.schedule is not None
    assert d.schedule.assignments["1"].end == pytest.approx(2.0)
    assert not d.reconfigured


def test_after_lidar_is_permanently_faulty_the_running_move_switches_to_the_camera() -> None:
    move = running("1", LIDAR)
    d = decision(move, faulty=frozenset({"lidar"}))
    assert d.reconfigured == {"1": CAM}
    assert d.configuration == SystemConfiguration({"1": CAM})
    assert d.transition == Transition(
        stop=("lidar_filter", "lidar"),
        start=("cam", "cam_to_lidar"),
        keep=frozenset({"robot_base"}),
    )


def test_without_an_alternative_the_running_task_is_cancelled_and_everything_stops() -> None:
    move = running("1", LIDAR)
    d = decision(move, robot=without("cam", "cam_to_lidar"), faulty=frozenset({"lidar"}))
    assert d.cancelled == {
        "1": "no provider for capability 'obstacle_scan': "
        "lidar_filter requires 'laser_scan' (lidar is permanently faulty)"
    }
    assert d.configuration == SystemConfiguration()
    assert d.transition.stop == ("robot_base", "lidar_filter", "lidar")


def test_a_task_of_a_permanently_faulty_behavior_is_cancelled() -> None:
    d = decision(task("1"), faulty=frozenset({"move_to"}))
    assert d.cancelled == {"1": "behavior move_to is permanently faulty"}
    assert not d.start_now


def test_a_deadline_shorter_than_the_task_cancels_it() -> None:
    d = decision(task("1", duration=5.0, deadline=NOW + 2.0))
    assert d.cancelled["1"].startswith("deadline 2 s cannot be met")


def test_the_ratings_the_knowledge_base_holds_choose_the_providers() -> None:
    d = decision(task("1"), ratings={"lidar_filter": 1.0})
    assert d.start_now == {"1": CAM}


def test_a_partner_that_ended_cannot_start_with_anyone_and_one_never_asked_for_is_ignored() -> None:
    ended = task("1", phase=TaskPhase.SUCCEEDED)
    d = decision(ended, task("2", together=("1",)), task("3", "take_picture", together=("99",)))
    assert d.cancelled == {"2": "must start together with unknown request '1'"}
    assert set(d.start_now) == {"3"}


def test_ended_tasks_leave_nothing_running_and_need_no_schedule() -> None:
    done = running("1", LIDAR)
    d = decision(dataclasses.replace(done, phase=TaskPhase.SUCCEEDED), running=on(done))
    assert d.schedule is None
    assert d.configuration == SystemConfiguration()
    assert d.transition.stop == ("robot_base", "lidar_filter", "lidar")


def test_a_picture_shares_the_camera_with_a_move_that_runs_on_it() -> None:
    move = running("1", CAM)
    d = decision(move, task("2", "take_picture"), faulty=frozenset({"lidar"}))
    assert d.start_now == {"2": {"camera": "cam"}}
    assert d.transition.empty  # cam runs already
    assert d.configuration.users["cam"] == {"1", "2"}


def test_the_same_situation_gives_the_same_decision() -> None:
    tasks = (running("1", LIDAR, began=NOW - 3.0), task("2"), task("3", "take_picture"))
    first, second = decision(*tasks), decision(*tasks)
    assert dataclasses.replace(first, schedule=None) == dataclasses.replace(second, schedule=None)


def kept(
    decided: Decision,
    running: SystemConfiguration,
    *,
    upcoming: tuple[str, ...] = (),
    lingering: frozenset[str] = frozenset(),
    faulty: frozenset[str] = frozenset(),
) -> Decision:
    return keep_running(
        decided, running, robot=usecase_robot(), faulty=faulty, upcoming=upcoming,
        lingering=lingering,
    )  # fmt: skip


def test_what_an_upcoming_step_needs_keeps_running_when_the_step_before_ends() -> None:
    ended = dataclasses.replace(running("1", LIDAR), phase=TaskPhase.SUCCEEDED)
    was = on(running("1", LIDAR))
    assert decision(ended, running=was).transition.stop  # without a word of what comes
    after = kept(decision(ended, running=was), was, upcoming=("take_picture", "move_to"))
    assert after.transition.empty
    assert after.configuration.functionalities == set(LIDAR.values())
    assert not after.configuration.held  # no task holds them: a reservation does


def test_upcoming_steps_keep_only_what_runs_and_is_usable() -> None:
    was = on(running("1", LIDAR))
    after = kept(decision(running=was), was, upcoming=("take_picture",))  # cam does not run
    assert after.configuration.functionalities == frozenset()
    faulty = kept(decision(running=was), was, upcoming=("move_to",), faulty=frozenset({"lidar"}))
    assert faulty.configuration.functionalities == frozenset()  # lidar_filter sits on lidar
    assert set(faulty.transition.stop) == set(LIDAR.values())


def test_once_no_step_to_come_needs_them_they_stop() -> None:
    was = kept(decision(running=on(running("1", LIDAR))), on(running("1", LIDAR)),
               upcoming=("move_to",)).configuration  # fmt: skip
    after = kept(Decision(configuration=SystemConfiguration(was.tasks)), was, upcoming=())
    assert set(after.transition.stop) == set(LIDAR.values())


def test_a_lingering_functionality_keeps_what_it_requires_running() -> None:
    was = on(running("1", LIDAR))
    after = kept(decision(running=was), was, lingering=frozenset({"lidar_filter"}))
    assert after.configuration.functionalities == {"lidar_filter", "lidar"}
    assert after.transition.stop == ("robot_base",)


def spare(*names: str) -> RobotDescription:
    """The use case with these functionalities as warm spares."""
    robot = usecase_robot()
    functionalities = {
        n: dataclasses.replace(f, standby=n in names) for n, f in robot.functionalities.items()
    }
    return dataclasses.replace(robot, functionalities=functionalities)


def test_a_warm_spare_and_what_it_runs_on_are_kept_idle_while_no_task_needs_them() -> None:
    robot = spare("cam_to_lidar")
    was = on(running("1", LIDAR))
    after = keep_running(decision(running=was), was, robot=robot, faulty=frozenset())
    assert after.configuration.functionalities == {"cam", "cam_to_lidar"}
    assert after.configuration.idle == {"cam", "cam_to_lidar"}
    assert set(after.transition.start) == {"cam", "cam_to_lidar"}
    held = keep_running(decision(running("1", CAM)), on(running("1", CAM)), robot=robot,
                        faulty=frozenset())  # fmt: skip
    assert held.configuration.idle == frozenset()  # a task holds it: it runs
    gone = keep_running(decision(running=was), was, robot=robot, faulty=frozenset({"cam"}))
    assert gone.configuration.functionalities == frozenset()  # no usable camera: no spare
