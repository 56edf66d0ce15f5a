"""ROS 2 programs, actions and services in the robot description: read, checked against
the robot's message definitions, and goal fields filled from objects' properties."""

from __future__ import annotations

from pathlib import Path

import pytest

from knowledge.description import GoalArg
from knowledge.errors import ConfigError
from knowledge.ros2_components import Ros2Call, Ros2ComponentSpec
from knowledge.validation import validate
from tests.conftest import ROOT

ROBOT = """\
robot: patrol
domain: {root}/domains/patrol/domain.pddl
problem: {root}/examples/ros2/problem.pddl
ros2:
  messages: [{root}/examples/ros2/msgs]
objects:
  lab: {{pose: {{position: {{x: 4.0}}}}}}
functionalities:
  navigator:
    command: [python, -c, pass]
    ros2: {navigator}
    provides: [navigation]
behaviors:
  navigate:
    ros2: {navigate}
    requires: [navigation]
tasks:
  move_to:
    behavior: navigate
    goal:
      pose.header.frame_id: map
      {field}: {value}
  localize:
    behavior: navigate
"""


def robot(
    tmp_path: Path,
    *,
    navigator: str = "{node: /navigator, lifecycle: true}",
    navigate: str = "{action: /navigate_to_pose, type: nav2_msgs/action/NavigateToPose}",
    field: str = "pose.pose",
    value: str = "?to.pose",
) -> Path:
    text = ROBOT.format(root=ROOT, navigator=navigator, navigate=navigate, field=field, value=value)
    path = tmp_path / "robot.yaml"
    path.write_text(text)
    return path


def test_nodes_lifecycle_nodes_and_actions_are_read_and_a_behavior_needs_no_program(
    tmp_path: Path,
) -> None:
    result = validate(robot(tmp_path))
    assert not result.errors, result.errors
    assert result.robot is not None
    assert result.robot.functionalities["navigator"].ros2 == Ros2ComponentSpec(
        "/navigator", True, None, 11
    )
    navigate = result.robot.behaviors["navigate"]
    assert navigate.command == ()
    assert navigate.ros2 is not None
    assert navigate.ros2.call == Ros2Call(
        "action", "/navigate_to_pose", "nav2_msgs/action/NavigateToPose"
    )
    assert result.robot.tasks["move_to"].goal["pose.pose"] == GoalArg("to", property="pose")
    assert result.robot.objects["lab"] == {"pose": {"position": {"x": 4.0}}}


@pytest.mark.parametrize(
    ("changes", "line", "message"),
    [
        ({"navigate": "{action: /navigate_to_pose, type: nav2_msgs/NavigateToPse}"}, 15,
         "behavior 'navigate': unknown ROS 2 action type 'nav2_msgs/action/NavigateToPse' "
         "(did you mean 'nav2_msgs/action/NavigateToPose'?)"),
        ({"field": "pose.pos"}, 22,
         "goal field 'pose.pos' of task 'move_to': geometry_msgs/msg/PoseStamped has no field "
         "'pos' (it has header, pose) (did you mean 'pose'?)"),
        ({"field": "pose.header.frame_id.x"}, 22,
         "goal field 'pose.header.frame_id.x' of task 'move_to': 'pose.header.frame_id' is a "
         "value, not a message with fields"),
        ({"value": "?to.position"}, 22,
         "goal field 'pose.pose' of task 'move_to' takes property 'position', which no object "
         "under 'objects:' has"),
        ({"navigator": "{lifecycle: true}"}, 11,
         "'ros2' of functionality 'navigator': a lifecycle node needs its 'node' name"),
        ({"navigator": "{node: /navigator, action: /go, type: a/b}"}, 11,
         "'ros2' of functionality 'navigator': a functionality takes no goals; an action "
         "belongs to a behavior"),
        ({"navigate": "{action: /go, service: /reset, type: std_srvs/srv/Trigger}"}, 15,
         "'ros2' of behavior 'navigate' has both an action and a service"),
        ({"navigate": "{node: /navigator}"}, 15,
         "'ros2' of behavior 'navigate': a ROS 2 behavior needs an 'action' or a 'service'"),
        ({"navigate": "{action: 2go, type: nav2_msgs/action/NavigateToPose}"}, 15,
         "'ros2' of behavior 'navigate': invalid ROS 2 action name '2go'"),
        ({"navigate": "{node: /navigator, action: /navigate_to_pose, "
                      "type: nav2_msgs/action/NavigateToPose}"}, 15,
         "'navigate' and 'navigator' are both ROS 2 node /navigator"),
    ],
)  # fmt: skip
def test_ros2_parts_of_components_are_checked_with_file_and_line(
    tmp_path: Path, changes: dict[str, str], line: int, message: str
) -> None:
    result = validate(robot(tmp_path, **changes))
    found = [(f.line, f.message) for f in result.errors]
    assert any(f_line == line and message in text for f_line, text in found), found


def test_components_with_ros2_parts_need_a_ros2_section(tmp_path: Path) -> None:
    text = robot(tmp_path).read_text()
    head, _, rest = text.partition("ros2:\n  messages")
    (tmp_path / "robot.yaml").write_text(head + rest.split("\n", 1)[1])
    result = validate(tmp_path / "robot.yaml")
    assert any("the robot has no 'ros2:' section" in f.message for f in result.errors)


def test_a_goal_field_takes_a_property_of_the_object_a_parameter_names() -> None:
    objects = {"lab": {"pose": {"position": {"x": 4.0}}}}
    assert GoalArg("to", property="pose.position").resolve({"to": "lab"}, objects) == {"x": 4.0}
    assert GoalArg("to").resolve({"to": "lab"}, objects) == "lab"
    assert GoalArg(constant="map").resolve({}, objects) == "map"
    with pytest.raises(ConfigError, match="object 'dock' has no property 'pose'"):
        GoalArg("to", property="pose").resolve({"to": "dock"}, objects)
