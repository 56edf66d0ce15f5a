"""The patrol robot of examples/ros2 run by a real ``dura run``: goals from ROS 2, the
diagnosis model's nodes from ROS 2 discovery, a crashed ROS 2 node restarted, and
``dura demo --ros2`` end to end."""

from __future__ import annotations

import json
import os
import queue
import signal
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import psutil
import pytest

from executive.bus.api.monitoring import DIAGNOSIS_MODEL_READ
from executive.ros2.names import dds_topic
from executive.ros2.participant import Participant
from executive.ros2.qos import dds_qos
from executive.ros2.types import TypeLibrary
from executive.testing.harness import RobotProcess, ServiceGroupProcess, robot_variant
from knowledge.ros2_messages import standard_store
from knowledge.ros2_spec import PROFILES
from tests.conftest import ROOT, run_dura, wait_for

pytestmark = pytest.mark.slow

EXAMPLE = ROOT / "examples" / "ros2" / "robot.yaml"
PATROL = "(and (visited lab) (visited office) (robot_at dock))"


@pytest.fixture
def patrol(domain: int, tmp_path: Path) -> Iterator[RobotProcess]:
    description = robot_variant(EXAMPLE, tmp_path / "robot", {"ros2": {"domain_id": domain}})
    with RobotProcess(description, tmp_path / "run") as robot:
        yield robot


class RosUser:
    """What a ROS 2 user does: publish goals on /dura/goals and read the replies."""

    def __init__(self, participant: Participant) -> None:
        self.library = TypeLibrary(standard_store("jazzy"), "jazzy")
        string = self.library.idl("std_msgs/msg/String")
        qos = dds_qos(PROFILES["default"])
        self.replies: queue.Queue[dict[str, Any]] = queue.Queue()
        decode = self.library.decoder("std_msgs/msg/String")

        def replied(samples: list[Any], received: float) -> None:
            for data, info in samples:
                if info.valid_data:
                    self.replies.put(json.loads(decode(data)["data"]))

        participant.reader(dds_topic("/dura/goals/replies"), string, qos, replied)
        self.goals = participant.writer(dds_topic("/dura/goals"), string, qos)

    def submit(self, text: str) -> dict[str, Any]:
        assert wait_for(lambda: self.goals.matched() > 0, timeout=20)
        self.goals.write(self.library.create("std_msgs/msg/String", {"data": text}))
        return self.replies.get(timeout=20)


def test_a_ros2_robot_takes_goals_from_ros2_diagnoses_its_nodes_from_the_graph_and_restarts_a_crashed_node(
    patrol: RobotProcess, domain: int
) -> None:
    with Participant(domain, name="ros_user") as participant:
        user = RosUser(participant)
        refused = user.submit("(visited lob)")
        assert refused["accepted"] is False
        assert "unknown object 'lob'" in refused["reason"], refused
        accepted = user.submit(json.dumps({"expression": PATROL, "priority": 3}))
        assert accepted["accepted"] is True, accepted
        goal = int(accepted["goal"]["id"])
        assert patrol.goal(goal).priority == 3

    def model() -> dict[str, tuple[list[str], list[str]]]:
        reply = DIAGNOSIS_MODEL_READ.call(patrol.bus)
        nodes = (reply.model or {}).get("nodes", [])
        return {n["name"]: (sorted(n["sub_topic"]), sorted(n["pub_topic"])) for n in nodes}

    expected = {"lidar": ([], ["scan"]), "odometry": (["cmd_vel"], ["odom"]),
                "navigator": (["odom", "scan"], ["cmd_vel", "navigator/transition_event"])}  # fmt: skip
    assert wait_for(lambda: all(model().get(n) == t for n, t in expected.items()), timeout=40)

    components = patrol.status().components
    assert isinstance(components, list), components  # the launcher answered
    lidar = next(c for c in components if c.component == "lidar")
    [program] = psutil.Process(lidar.pid).children()
    program.send_signal(signal.SIGKILL)  # the ROS 2 node crashes while the robot drives
    patrol.wait_for(goal, "achieved", timeout=90)
    faults = [e for e in patrol.events("FAULT") if e.subject == "lidar"]
    assert faults, patrol.events()
    assert len([e for e in patrol.events("COMPONENT_READY") if e.subject == "lidar"]) >= 2


def test_dura_demo_ros2_runs_end_to_end(tmp_path: Path) -> None:
    env_before = os.environ.get("CYCLONEDDS_URI")
    done = run_dura("demo", "--ros2", "--json", "--keep", str(tmp_path), timeout=180)
    assert done.returncode == 0, done.stderr[-3000:] + done.stdout[-3000:]
    report = json.loads(done.stdout)
    assert report["ok"] and report["elapsed"] < 90
    assert [g["state"] for g in report["goals"]] == ["achieved"]
    assert [(f["name"], f["fault_count"]) for f in report["faults"]] == [("lidar", 1)]
    assert any(["lidar"] in d["diagnoses"] for d in report["diagnoses"])
    kinds = [e["kind"] for e in report["events"]]
    assert "TASK_PAUSED" in kinds and "TASK_RESUMED" in kinds
    assert report["ros2_diagnostic_arrays"] > 0
    assert os.environ.get("CYCLONEDDS_URI") == env_before


def test_a_ros2_robots_monitoring_and_high_level_apart_read_ros2_topics_themselves(
    domain: int, tmp_path: Path
) -> None:
    # the sensing rule reads /odom: near x = 0 the robot is at the dock
    rule = {"name": "at_dock", "topic": "odom", "field": "pose.pose.position.x",
            "fact": "(visited dock)", "below": 0.5}  # fmt: skip
    changes = {"ros2": {"domain_id": domain}, "sensing": [rule]}
    description = robot_variant(EXAMPLE, tmp_path / "robot", changes)
    split = ["--without", "monitoring", "--without", "planning"]
    with (
        RobotProcess(description, tmp_path / "run", run_args=split) as robot,
        ServiceGroupProcess(robot, "monitoring"),
        ServiceGroupProcess(robot, "planning"),
    ):
        goal = robot.submit_goal("(and (visited lab) (robot_at dock))")
        robot.wait_for(goal, "achieved", timeout=120)
        # the monitoring process's observers saw /scan and /odom: no silence taken for a fault
        assert robot.events("FAULT") == []
        # the planning process's sensing rule read /odom
        sensed = [e for e in robot.events("STATE_SET") if e.subject == "(visited dock)"]
        assert sensed and sensed[0].data["topic"] == "odom", robot.events("STATE_SET")
