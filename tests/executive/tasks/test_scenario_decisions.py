"""The decisions of the thesis scenarios (chapter 7) without processes: faults counted in
a real knowledge base, schedules from clingo, and the configuration transitions that
follow. The end-to-end scenarios with component processes build on these."""

from __future__ import annotations

import dataclasses
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

from executive.tasks.configuration import SystemConfiguration, Transition
from executive.tasks.faults import Faults, TaskAction, TaskUsage
from executive.tasks.schedule import Request
from executive.tasks.scheduler import Scheduler
from knowledge.description import RobotDescription
from knowledge.knowledge_base import KnowledgeBase
from tests.executive.tasks.scheduling_cases import usecase_robot


@pytest.fixture
def usecase() -> RobotDescription:
    return usecase_robot()


@pytest.fixture
def kb(tmp_path: Path) -> Iterator[KnowledgeBase]:
    with KnowledgeBase(tmp_path / "robot.db") as kb:
        yield kb


def without(robot: RobotDescription, *names: str) -> RobotDescription:
    kept = {n: f for n, f in robot.functionalities.items() if n not in names}
    return dataclasses.replace(robot, functionalities=kept)


def request(robot: RobotDescription, task: str, behavior: str, **more: Any) -> Request:
    return Request(task, behavior, robot.behaviors[behavior].requires, 10.0, **more)


def schedule(faults: Faults, requests: list[Request]) -> dict[str, dict[str, str]]:
    result = Scheduler(faults.functionalities()).schedule(requests, faulty=faults.faulty())
    assert result.cancelled == {}
    return {t: dict(a.providers) for t, a in result.assignments.items()}


def test_scenario_1_lidar_faulted_three_times_without_an_alternative_cancels_move_to(
    usecase: RobotDescription, kb: KnowledgeBase
) -> None:
    robot = without(usecase, "cam", "cam_to_lidar")
    faults = Faults(robot, kb)
    (providers,) = schedule(faults, [request(robot, "1", "move_to")]).values()
    running = TaskUsage("1", "move_to", frozenset(providers.values()))
    first, second, third = (faults.fault("lidar", "user restart", [running]) for _ in range(3))
    for decision in (first, second):
        assert decision.restart  # restart lidar; move_to is stopped and started again
        assert decision.tasks == {"1": TaskAction.RESTART}
    assert third.permanent
    assert set(third.unusable) == {"lidar", "lidar_filter"}
    again = request(robot, "1", "move_to", running=True, configuration=providers)
    result = Scheduler(faults.functionalities()).schedule([again], faulty=faults.faulty())
    assert result.cancelled == {
        "1": "no provider for capability 'obstacle_scan': "
        "lidar_filter requires 'laser_scan' (lidar is permanently faulty)"
    }


def test_scenario_2_after_the_third_fault_move_to_switches_to_cam_and_cam_to_lidar(
    usecase: RobotDescription, kb: KnowledgeBase
) -> None:
    faults = Faults(usecase, kb)
    providers = schedule(faults, [request(usecase, "1", "move_to")])["1"]
    configuration = SystemConfiguration().with_task("1", providers)
    assert SystemConfiguration().transition(configuration, usecase.functionalities.values()) == (
        Transition(start=("lidar", "lidar_filter", "robot_base"))
    )
    running = TaskUsage("1", "move_to", configuration.functionalities)
    *_, third = (faults.fault("lidar", "user restart", [running]) for _ in range(3))
    assert third.reschedule
    assert third.tasks == {"1": TaskAction.RESTART}
    again = request(usecase, "1", "move_to", running=True, configuration=providers)
    repaired = configuration.with_task("1", schedule(faults, [again])["1"])
    transition = configuration.transition(repaired, usecase.functionalities.values())
    assert transition == Transition(
        stop=("lidar_filter", "lidar"),
        start=("cam", "cam_to_lidar"),
        keep=frozenset({"robot_base"}),
    )


def test_scenario_3_the_second_move_to_waits_for_the_first(
    usecase: RobotDescription, kb: KnowledgeBase
) -> None:
    faults = Faults(usecase, kb)
    first = schedule(faults, [request(usecase, "1", "move_to")])["1"]
    running = request(usecase, "1", "move_to", running=True, configuration=first)
    result = Scheduler(faults.functionalities()).schedule(
        [running, request(usecase, "2", "move_to")], faulty=faults.faulty()
    )
    assert result.assignments["2"].after == {"1"}
    assert result.assignments["2"].start == result.assignments["1"].end
    # when the first ends, the second takes over lidar, lidar_filter and robot_base
    now = SystemConfiguration().with_task("1", first)
    then = now.without_task("1").with_task("2", result.assignments["2"].providers)
    assert now.transition(then, usecase.functionalities.values()).empty


def test_scenario_4_cam_runs_while_move_to_or_take_picture_needs_it(
    usecase: RobotDescription, kb: KnowledgeBase
) -> None:
    faults = Faults(usecase, kb)
    requests = [request(usecase, "1", "move_to"), request(usecase, "2", "take_picture")]
    before = schedule(faults, requests)
    configuration = SystemConfiguration(before)
    assert configuration.users["cam"] == {"2"}
    tasks = [
        TaskUsage("1", "move_to", frozenset(before["1"].values())),
        TaskUsage("2", "take_picture", frozenset(before["2"].values())),
    ]
    *_, third = (faults.fault("lidar", "user restart", tasks) for _ in range(3))
    assert third.tasks == {"1": TaskAction.RESTART}  # take_picture keeps running
    running = [
        request(usecase, "1", "move_to", running=True, configuration=before["1"]),
        request(usecase, "2", "take_picture", running=True, configuration=before["2"]),
    ]
    after = SystemConfiguration(schedule(faults, running))
    assert after.users["cam"] == {"1", "2"}
    transition = configuration.transition(after, usecase.functionalities.values())
    assert transition.start == ("cam_to_lidar",)  # cam runs already, for take_picture
    assert transition.stop == ("lidar_filter", "lidar")
    done = after.transition(after.without_task("2"), usecase.functionalities.values())
    assert done.empty  # cam stays for move_to
