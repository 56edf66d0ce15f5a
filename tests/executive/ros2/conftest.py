"""Fixtures of the ROS 2 tests: real Cyclone DDS on loopback, nothing left behind.

DDS stays on 127.0.0.1 with multicast off (unicast discovery to the loopback peer), in
a domain picked at random for this test process, so that test runs of other people on
the same machine never meet. After every test no participant of ours may be left.
"""

from __future__ import annotations

import os
import random
from collections.abc import Iterator
from pathlib import Path

import pytest

from executive.bus.service import Context
from executive.bus.session import Bus
from executive.ros2.link import Ros2Link
from executive.ros2.participant import participants_in
from knowledge.description import RobotDescription
from knowledge.knowledge_base import KnowledgeBase
from knowledge.robot import read_robot
from monitoring.observer_manager import ObserverManager
from tests.executive.ros2.peer import LOOPBACK, RosPeer
from tests.monitoring.harness import Observations, write_robot

ROS2 = """\
ros2:
  domain_id: {domain}
  topics:
    /scan: {{type: sensor_msgs/msg/LaserScan}}
    /scan_filtered: {{type: sensor_msgs/LaserScan, qos: default}}
    /odom: {{type: nav_msgs/msg/Odometry}}
    /imu: {{type: sensor_msgs/msg/Imu}}
    /cmd_vel: {{type: geometry_msgs/msg/Twist}}
    /battery: {{type: std_msgs/msg/Float64}}
    /mystery: {{}}
    /robot1/scan: {{type: sensor_msgs/msg/LaserScan}}
"""


@pytest.fixture(scope="session")
def domain(tmp_path_factory: pytest.TempPathFactory) -> Iterator[int]:
    """This test process's DDS domain (the configuration is in CYCLONEDDS_URI)."""
    config = tmp_path_factory.mktemp("dds") / "cyclonedds.xml"
    config.write_text(LOOPBACK)
    before = os.environ.get("CYCLONEDDS_URI")
    os.environ["CYCLONEDDS_URI"] = config.as_uri()  # child processes inherit it
    yield random.SystemRandom().randint(1, 230)
    if before is None:
        os.environ.pop("CYCLONEDDS_URI", None)
    else:
        os.environ["CYCLONEDDS_URI"] = before


@pytest.fixture(autouse=True)
def nothing_left(domain: int) -> Iterator[None]:
    """Every test deletes every participant it made."""
    yield
    assert participants_in(domain) == 0, "a DDS participant was left open"


@pytest.fixture
def ros2_robot(tmp_path: Path, endpoint: str, domain: int) -> RobotDescription:
    robot, findings = read_robot(write_robot(tmp_path, endpoint, extra=ROS2.format(domain=domain)))
    assert robot is not None and robot.ros2 is not None, findings
    assert not [f for f in findings if f.is_error], findings
    return robot


@pytest.fixture
def link(ros2_robot: RobotDescription) -> Iterator[Ros2Link]:
    assert ros2_robot.ros2 is not None
    with Ros2Link(ros2_robot.ros2) as opened:
        yield opened


@pytest.fixture
def peer(domain: int) -> Iterator[RosPeer]:
    with RosPeer(domain) as opened:
        yield opened


@pytest.fixture
def bus(ros2_robot: RobotDescription) -> Iterator[Bus]:
    with Bus(ros2_robot.name, name="executive", endpoint=ros2_robot.endpoint, listen=True) as b:
        yield b


@pytest.fixture
def context(ros2_robot: RobotDescription, bus: Bus, tmp_path: Path) -> Iterator[Context]:
    with KnowledgeBase(tmp_path / "kb.db") as kb:
        yield Context(ros2_robot, bus, kb)


@pytest.fixture
def manager(context: Context, link: Ros2Link) -> Iterator[ObserverManager]:
    """An observer manager that reads the robot's ROS 2 topics through the link."""
    started = ObserverManager(context, sources=[link.topics])
    started.configure()
    started.activate()
    try:
        yield started
    finally:
        started.shutdown()


@pytest.fixture
def observations(bus: Bus) -> Observations:
    return Observations(bus)
