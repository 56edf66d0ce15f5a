"""Reading a robot description gives typed, frozen data."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import pytest

from knowledge.description import BehaviorSpec, FunctionalitySpec, GoalArg, Kind
from knowledge.errors import ConfigError
from knowledge.robot import load_robot, read_robot


def test_the_use_case_has_five_functionalities_two_behaviors_and_two_tasks(
    usecase_path: Path,
) -> None:
    robot = load_robot(usecase_path)
    assert robot.name == "usecase"
    assert set(robot.functionalities) == {
        "lidar",
        "lidar_filter",
        "robot_base",
        "cam",
        "cam_to_lidar",
    }
    assert set(robot.behaviors) == {"move_to", "take_picture"}
    assert set(robot.tasks) == {"move_to", "take_picture"}
    assert robot.domain.name == "domain.pddl" and robot.domain.is_absolute()


def test_the_filtered_scan_is_provided_by_lidar_filter_first_then_cam_to_lidar(
    usecase_path: Path,
) -> None:
    robot = load_robot(usecase_path)
    assert [f.name for f in robot.providers("obstacle_scan")] == ["lidar_filter", "cam_to_lidar"]
    assert robot.functionalities["lidar_filter"].requires == ("laser_scan",)
    assert robot.functionalities["cam_to_lidar"].requires == ("camera",)


def test_the_robot_base_is_not_shareable(usecase_path: Path) -> None:
    robot = load_robot(usecase_path)
    assert robot.functionalities["robot_base"].shareable is False
    assert robot.functionalities["lidar"].shareable is True


def test_components_are_typed_and_frozen(usecase_path: Path) -> None:
    robot = load_robot(usecase_path)
    lidar = robot.component("lidar")
    move_to = robot.component("move_to")
    assert isinstance(lidar, FunctionalitySpec) and lidar.kind is Kind.FUNCTIONALITY
    assert isinstance(move_to, BehaviorSpec) and move_to.kind is Kind.BEHAVIOR
    assert lidar.command == ("python", "-m", "components.lidar")
    assert lidar.params == {"rate": 10.0}
    assert lidar.max_faults == 3
    assert move_to.reconfigurable is False
    with pytest.raises(dataclasses.FrozenInstanceError):
        lidar.rating = 0  # type: ignore[misc]


def test_observers_keep_the_thesis_schema_as_written(usecase_path: Path) -> None:
    lidar = load_robot(usecase_path).component("lidar")
    kinds = [o.type for o in lidar.observers]
    assert kinds == ["frequency", "timeout"]
    assert lidar.observers[0].config["topics"][0]["name"] == "scan"


def test_every_key_inside_an_observer_entry_keeps_its_line(usecase_path: Path) -> None:
    spec = load_robot(usecase_path).component("lidar").observers[0]
    lines = usecase_path.read_text().splitlines()
    window = spec.line_of("topics.0.callerids.0.filter.window_size")
    assert "window_size: 10" in lines[window - 1]
    assert "filter:" in lines[spec.line_of("topics.0.callerids.0.filter.absent") - 1]


def test_task_goals_map_action_parameters_onto_behavior_fields(usecase_path: Path) -> None:
    task = load_robot(usecase_path).tasks["move_to"]
    assert task.behavior == "move_to"
    assert task.goal == {"start": GoalArg(parameter="from"), "target": GoalArg(parameter="to")}
    assert {k: a.resolve({"from": "dock", "to": "lab"}) for k, a in task.goal.items()} == {
        "start": "dock",
        "target": "lab",
    }


def test_a_goal_field_may_be_a_constant(tmp_path: Path) -> None:
    (tmp_path / "d.pddl").write_text(
        "(define (domain d) (:requirements :strips) (:action a :parameters ()))"
    )
    (tmp_path / "r.yaml").write_text(
        "robot: r\ndomain: d.pddl\nbehaviors:\n  b: {command: [x]}\ntasks:\n  a:\n    behavior: b\n"
        "    goal:\n      speed: 0.5\n"
    )
    robot, findings = read_robot(tmp_path / "r.yaml")
    assert robot is not None and not findings
    assert robot.tasks["a"].goal["speed"].resolve({}) == 0.5


def test_loading_an_invalid_description_raises_one_line_with_the_first_problem(
    tmp_path: Path,
) -> None:
    (tmp_path / "r.yaml").write_text("robot: r\ndomain: none.pddl\nfunctionalitis: {}\n")
    with pytest.raises(ConfigError) as error:
        load_robot(tmp_path / "r.yaml")
    message = str(error.value)
    assert "\n" not in message
    assert message.startswith(f"{tmp_path / 'r.yaml'}:2: 'domain' names no file")
    assert "and 1 more" in message
