from __future__ import annotations

import dataclasses
from collections.abc import Iterator
from pathlib import Path

import pytest

from executive.tasks.faults import Faults, TaskAction, TaskUsage
from knowledge.description import Kind, RobotDescription
from knowledge.errors import KnowledgeError
from knowledge.knowledge_base import KnowledgeBase
from tests.executive.tasks.scheduling_cases import usecase_robot

LIDAR = frozenset({"lidar", "lidar_filter", "robot_base"})
CAM = frozenset({"cam", "cam_to_lidar", "robot_base"})


@pytest.fixture
def robot() -> RobotDescription:
    return usecase_robot()


@pytest.fixture
def kb(tmp_path: Path) -> Iterator[KnowledgeBase]:
    with KnowledgeBase(tmp_path / "robot.db") as kb:
        yield kb


def move_to(functionalities: frozenset[str] = LIDAR) -> TaskUsage:
    return TaskUsage("1", "move_to", functionalities)


def test_a_functionality_below_max_faults_is_restarted_and_its_task_restarts_its_behavior(
    robot: RobotDescription, kb: KnowledgeBase
) -> None:
    faults = Faults(robot, kb)
    decision = faults.fault("lidar", "restart requested", [move_to()])
    assert decision.kind is Kind.FUNCTIONALITY
    assert (decision.count, decision.permanent) == (1, False)
    assert decision.restart
    assert not decision.reschedule
    # move_to is not reconfigurable: stop it, start it again on the repaired configuration
    assert decision.tasks == {"1": TaskAction.RESTART}
    assert kb.component("lidar").fault_count == 1


def test_a_reconfigurable_behavior_pauses_while_its_configuration_is_repaired(
    robot: RobotDescription, kb: KnowledgeBase
) -> None:
    reconfigurable = dataclasses.replace(robot.behaviors["move_to"], reconfigurable=True)
    robot = dataclasses.replace(robot, behaviors={**robot.behaviors, "move_to": reconfigurable})
    decision = Faults(robot, kb).fault("lidar", "crashed", [move_to()])
    assert decision.tasks == {"1": TaskAction.PAUSE}


def test_the_third_fault_makes_lidar_and_lidar_filter_permanently_faulty(
    robot: RobotDescription, kb: KnowledgeBase
) -> None:
    faults = Faults(robot, kb)
    others = TaskUsage("2", "take_picture", frozenset({"cam"}))
    decisions = [faults.fault("lidar", "restart requested", [move_to(), others]) for _ in range(3)]
    assert [(d.count, d.permanent) for d in decisions] == [(1, False), (2, False), (3, True)]
    last = decisions[-1]
    assert not last.restart
    assert last.reschedule
    assert last.unusable == {
        "lidar": "is permanently faulty",
        "lidar_filter": "requires 'laser_scan' (lidar is permanently faulty)",
    }
    assert last.tasks == {"1": TaskAction.RESTART}  # take_picture does not use them
    assert faults.faulty() == {"lidar"}
    assert faults.availability().usable == {"robot_base", "cam", "cam_to_lidar"}
    assert [e.subject for e in kb.events(kind="PERMANENT_FAULT")] == ["lidar"]


def test_a_task_on_a_functionality_that_lost_its_base_is_hit_too(
    robot: RobotDescription, kb: KnowledgeBase
) -> None:
    faults = Faults(robot, kb)
    on_filter = TaskUsage("3", "move_to", frozenset({"lidar_filter"}))
    decision = faults.fault("lidar", "diagnosed faulty", [on_filter], permanent=True)
    assert decision.permanent
    assert decision.count == 1
    assert decision.tasks == {"3": TaskAction.RESTART}


def test_faults_and_permanent_faults_are_remembered_by_a_new_executive(
    robot: RobotDescription, tmp_path: Path
) -> None:
    with KnowledgeBase(tmp_path / "robot.db") as kb:
        faults = Faults(robot, kb)
        for _ in range(3):
            faults.fault("lidar", "crashed")
    with KnowledgeBase(tmp_path / "robot.db") as kb:
        faults = Faults(robot, kb)
        assert faults.faulty() == {"lidar"}
        assert kb.component("lidar").fault_count == 3
        decision = faults.fault("lidar", "crashed again")
        assert decision.count == 4
        assert decision.unusable == {}  # nothing new: it was faulty already


def test_resetting_a_component_after_maintenance_makes_it_usable_again(
    robot: RobotDescription, kb: KnowledgeBase
) -> None:
    faults = Faults(robot, kb)
    faults.fault("lidar", "broken", permanent=True)
    assert faults.reset("lidar") == ["lidar", "lidar_filter"]
    assert faults.faulty() == frozenset()
    assert kb.component("lidar").fault_count == 0


def test_a_failing_behavior_restarts_up_to_max_restarts_then_its_task_fails(
    robot: RobotDescription, kb: KnowledgeBase
) -> None:
    faults = Faults(robot, kb)
    task = TaskUsage("7", "take_picture", frozenset({"cam"}))  # max_restarts: 2
    actions = [faults.fault("take_picture", "exited 1", [task]).tasks["7"] for _ in range(3)]
    assert actions == [TaskAction.RESTART, TaskAction.RESTART, TaskAction.FAIL]
    decision = faults.fault("take_picture", "exited 1", [TaskUsage("8", "take_picture")])
    assert decision.tasks == {"8": TaskAction.RESTART}  # a new task starts counting afresh
    assert not decision.restart
    assert not decision.permanent  # behaviors count faults but never become faulty by count
    assert kb.component("take_picture").fault_count == 4


def test_restarts_of_a_finished_task_are_forgotten(
    robot: RobotDescription, kb: KnowledgeBase
) -> None:
    faults = Faults(robot, kb)
    task = TaskUsage("7", "take_picture")
    faults.fault("take_picture", "exited 1", [task])
    faults.fault("take_picture", "exited 1", [task])
    faults.finished("7")
    assert faults.fault("take_picture", "exited 1", [task]).tasks == {"7": TaskAction.RESTART}


def test_a_behavior_marked_faulty_fails_its_task(
    robot: RobotDescription, kb: KnowledgeBase
) -> None:
    decision = Faults(robot, kb).fault("move_to", "marked", [move_to()], permanent=True)
    assert decision.permanent
    assert decision.tasks == {"1": TaskAction.FAIL}


def test_the_knowledge_base_ratings_are_the_ones_to_schedule_with(
    robot: RobotDescription, kb: KnowledgeBase
) -> None:
    faults = Faults(robot, kb)
    kb.set_rating("cam_to_lidar", 42)
    ratings = {f.name: f.rating for f in faults.functionalities()}
    assert ratings["cam_to_lidar"] == 42
    assert ratings["lidar"] == 10


def test_a_fault_of_an_unknown_component_is_refused(
    robot: RobotDescription, kb: KnowledgeBase
) -> None:
    with pytest.raises(KnowledgeError, match="robot 'usecase' has no component 'lidr'"):
        Faults(robot, kb).fault("lidr", "typo")
    assert kb.events(kind="FAULT") == []
