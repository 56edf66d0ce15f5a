"""The ros2 section of a robot description and ROS 2's names on the DDS wire."""

from __future__ import annotations

from pathlib import Path

import pytest

from executive.ros2 import names
from knowledge.ros2_spec import PROFILES, QosProfile, Ros2TopicSpec
from knowledge.validation import validate
from tests.monitoring.harness import write_robot

GOOD = """\
ros2:
  domain_id: 42
  distribution: humble
  node: watcher
  messages: [msgs]
  diagnostics: /robot/diagnostics
  events: null
  topics:
    /scan: {type: sensor_msgs/LaserScan, qos: default}
    odom:
    robot1/battery: {type: my_msgs/msg/Battery, qos: {reliability: reliable, depth: 3}}
"""


def messages(folder: Path, text: str = "std_msgs/Header header\nfloat32 percent\n") -> None:
    (folder / "msgs" / "my_msgs" / "msg").mkdir(parents=True)
    (folder / "msgs" / "my_msgs" / "msg" / "Battery.msg").write_text(text)


def test_a_ros2_section_is_read_with_its_topics_types_and_qos(tmp_path: Path) -> None:
    messages(tmp_path)
    result = validate(write_robot(tmp_path, "tcp/127.0.0.1:7447", extra=GOOD))
    assert not result.errors, result.errors
    assert result.robot is not None and result.robot.ros2 is not None
    spec = result.robot.ros2
    assert (spec.domain_id, spec.distribution, spec.node) == (42, "humble", "watcher")
    assert spec.messages == ((tmp_path / "msgs").resolve(),)
    assert (spec.diagnostics, spec.events) == ("/robot/diagnostics", None)
    assert spec.topic("/scan") == Ros2TopicSpec(
        "/scan", "sensor_msgs/msg/LaserScan", PROFILES["default"], 27
    )
    assert spec.topic("odom") == Ros2TopicSpec("/odom", None, PROFILES["sensor_data"], 28)
    battery = spec.topic("robot1/battery")
    assert battery is not None and battery.type == "my_msgs/msg/Battery"
    assert battery.qos == QosProfile("reliable", "volatile", "keep_last", 3)


@pytest.mark.parametrize(
    ("section", "line", "message"),
    [
        ("  domain_id: 300\n", 20, "'domain_id' of 'ros2' of the robot description must be at most 232"),
        ("  distribution: humbel\n", 20, "unknown distribution 'humbel' in 'ros2' of the robot description (choose from foxy, galactic, humble, iron, jazzy, kilted, lyrical) (did you mean 'humble'?)"),
        ("  transport: zenoh\n", 20, "unknown transport 'zenoh'"),
        ("  nodes: {}\n", 20, "unknown key 'nodes' in 'ros2' of the robot description (did you mean 'node'?)"),
        ("  topics:\n    /scan: {type: sensor_msgs/msg/LaserScn}\n", 21, "ROS 2 topic '/scan' has unknown message type 'sensor_msgs/msg/LaserScn' (did you mean 'sensor_msgs/msg/LaserScan'?)"),
        ("  topics:\n    /scan: {tpye: sensor_msgs/msg/LaserScan}\n", 21, "unknown key 'tpye' in ROS 2 topic '/scan' (did you mean 'type'?)"),
        ("  topics:\n    /scan: {qos: sensor}\n", 21, "unknown QoS profile 'sensor' of ROS 2 topic '/scan'"),
        ("  topics:\n    /scan: {qos: {reliability: sometimes}}\n", 21, "unknown reliability 'sometimes' in the QoS of ROS 2 topic '/scan' (choose from reliable, best_effort)"),
        ("  topics:\n    /2scan: {}\n", 21, "invalid ROS 2 topic name '/2scan'"),
    ],
)  # fmt: skip
def test_a_bad_ros2_section_is_a_file_line_error(  # the section starts at line 19
    tmp_path: Path, section: str, line: int, message: str
) -> None:
    path = write_robot(tmp_path, "tcp/127.0.0.1:7447", extra="ros2:\n" + section)
    errors = [str(e) for e in validate(path).errors]
    assert any(e.startswith(f"{path}:{line}: {message}") for e in errors), errors


def test_a_bad_message_file_is_an_error_at_its_own_line(tmp_path: Path) -> None:
    messages(tmp_path, "std_msgs/Header header\nfloat32 percent\nPoint where\nwstring name\n")
    extra = "ros2:\n  messages: [msgs]\n  topics:\n    /battery: {type: my_msgs/Battery}\n"
    errors = [
        str(e) for e in validate(write_robot(tmp_path, "tcp/127.0.0.1:7447", extra=extra)).errors
    ]
    battery = tmp_path / "msgs" / "my_msgs" / "msg" / "Battery.msg"
    assert f"{battery.resolve()}:4: wstring fields are not supported yet" in errors
    assert (
        f"{battery.resolve()}:3: field 'where' of my_msgs/msg/Battery has unknown type "
        "'my_msgs/msg/Point' (did you mean 'geometry_msgs/msg/Point'?)"
    ) in errors


def test_ros2_names_follow_the_rmw_conventions() -> None:
    assert names.dds_topic("/scan") == "rt/scan"
    assert names.ros_topic("rt/robot1/scan") == "/robot1/scan"
    assert names.ros_topic("ros_discovery_info") is None
    assert names.request_topic("/add_two_ints") == "rq/add_two_intsRequest"
    assert names.reply_topic("add_two_ints") == "rr/add_two_intsReply"
    assert names.service_of("rq/add_two_intsRequest") == "/add_two_ints"
    assert names.service_of("rt/scan") is None
    action = names.action_names("/navigate_to_pose")
    assert names.request_topic(action.send_goal) == "rq/navigate_to_pose/_action/send_goalRequest"
    assert names.dds_topic(action.feedback) == "rt/navigate_to_pose/_action/feedback"
    assert names.dds_type("sensor_msgs/msg/LaserScan") == "sensor_msgs::msg::dds_::LaserScan_"
    assert names.dds_type("nav2_msgs/action/NavigateToPose_SendGoal_Request") == (
        "nav2_msgs::action::dds_::NavigateToPose_SendGoal_Request_"
    )
    assert names.ros_type("std_msgs::msg::dds_::String_") == "std_msgs/msg/String"
    assert names.ros_type("String") is None
    assert names.node_name("/robot1/", "lidar") == "/robot1/lidar"
    assert names.caller_id(names.node_name("/", "lidar")) == "lidar"


def test_the_goals_topic_is_dura_goals_unless_set_or_turned_off(tmp_path: Path) -> None:
    for extra, expected in (("ros2: {}\n", "/dura/goals"), ("ros2: {goals: patrol/goals}\n",
                            "/patrol/goals"), ("ros2: {goals: null}\n", None)):  # fmt: skip
        result = validate(write_robot(tmp_path, "tcp/127.0.0.1:7447", extra=extra))
        assert not result.errors, result.errors
        assert result.robot is not None and result.robot.ros2 is not None
        assert result.robot.ros2.goals == expected
