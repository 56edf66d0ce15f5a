"""What the launcher runs for a ROS 2 program, and how goal fields become ROS 2 messages."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from executive.ros2.types import TypeLibrary
from executive.runtime.ros2_goals import nested, typed
from executive.runtime.ros2_launch import ENV_CONFIG, HOST_MODULE, HostConfig, launch_program
from executive.sdk import GoalFailed
from knowledge.robot import read_robot
from knowledge.ros2_messages import message_store
from tests.conftest import ROOT

EXAMPLE = ROOT / "examples" / "ros2" / "robot.yaml"
NAV_GOAL = "nav2_msgs/action/NavigateToPose_Goal"


@pytest.fixture(scope="module")
def library() -> TypeLibrary:
    return TypeLibrary(message_store("jazzy", [Path(ROOT / "examples" / "ros2" / "msgs")]), "jazzy")


def test_a_ros2_program_runs_under_its_host_in_the_robots_domain() -> None:
    robot, _ = read_robot(EXAMPLE)
    assert robot is not None
    argv, env = launch_program(robot, robot.components["navigator"])
    assert argv == ["python", "-m", HOST_MODULE, "--", "python", "-m", "nodes.navigator"]
    assert env["ROS_DOMAIN_ID"] == "0"
    config = HostConfig.from_json(env[ENV_CONFIG])
    assert (config.node, config.lifecycle, config.call) == ("/navigator", True, None)
    argv, env = launch_program(robot, robot.components["navigate"])
    assert argv == ["python", "-m", HOST_MODULE, "--"]  # dura's action client alone
    assert json.loads(env[ENV_CONFIG])["call"] == {
        "kind": "action", "name": "/navigate_to_pose",
        "type": "nav2_msgs/action/NavigateToPose", "wait": 5.0,
    }  # fmt: skip


def test_a_component_without_ros2_runs_its_own_command() -> None:
    robot, _ = read_robot(ROOT / "examples" / "usecase" / "robot.yaml")
    assert robot is not None
    assert launch_program(robot, robot.components["lidar"]) == (
        ["python", "-m", "components.lidar"], {},
    )  # fmt: skip


def test_dotted_goal_fields_and_whole_messages_merge_into_one_goal(library: TypeLibrary) -> None:
    goal = {
        "pose.header.frame_id": "map",
        "pose.pose": {"position": {"x": 4.0}, "orientation": {"w": 1.0}},
        "pose.pose.position.y": "3",  # text from the command line
        "behavior_tree": "",
    }
    message = typed(library, NAV_GOAL, nested(goal))
    assert message == {
        "behavior_tree": "",
        "pose": {"header": {"frame_id": "map"},
                 "pose": {"position": {"x": 4.0, "y": 3.0}, "orientation": {"w": 1.0}}},
    }  # fmt: skip
    library.create(NAV_GOAL, message)  # a valid goal


@pytest.mark.parametrize(
    ("goal", "reason"),
    [
        ({"pose.header.frame_id": "map", "pose.header.frame_id.x": 1},
         "goal field 'pose.header.frame_id.x' lies inside 'frame_id', which is a value"),
        ({"pose.pose.position.x": "far"}, "field 'x' is a float64, not 'far'"),
        ({"pos": 1}, "nav2_msgs/action/NavigateToPose_Goal has no field 'pos'"),
    ],
)  # fmt: skip
def test_goal_fields_that_do_not_fit_the_goal_type_fail_the_goal_with_the_reason(
    library: TypeLibrary, goal: dict[str, object], reason: str
) -> None:
    with pytest.raises(GoalFailed, match=reason):
        typed(library, NAV_GOAL, nested(goal))
