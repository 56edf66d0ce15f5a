"""Observers of every type on ROS 2 topics, fed by a plain DDS peer acting as ROS 2 nodes.

Each test runs the observer manager with the robot's ROS 2 topics as a topic source and
checks that the observations are what the same observers report on dura's own bus.
"""

from __future__ import annotations

import logging
import threading
import time
from typing import Any

import pytest
from cyclonedds._clayer import ddspy_write

from executive.bus.payloads import GENERAL_ERROR, TIMEOUT
from executive.ros2.link import Ros2Link
from monitoring.observer_manager import ObserverManager
from tests.conftest import wait_for
from tests.executive.ros2.messages import (
    Float64,
    Header,
    Imu,
    LaserScan,
    Odometry,
    Thing,
    Twist,
    TwistWithCovariance,
    Vector3,
)
from tests.executive.ros2.peer import RosPeer, scan, stamp, streaming
from tests.monitoring.harness import Observations, seen

OK = {"state": "ok", "number": 1}


def frequency(topic: str, groups: list[list[str]], *, rate: float = 5.0) -> dict[str, Any]:
    return {
        "type": "hz",
        "main_loop_rate": rate,
        "start_up_time": 0.5,
        "topics": [
            {
                "name": topic,
                "callerids": [
                    {
                        "callerid": callers,
                        "filter": {"type": "mean", "window_size": 10},
                        "states": [
                            {**OK, "frequency": {"type": "greater_than", "greater_than": 0}}
                        ],
                    }
                    for callers in groups
                ],
            }
        ],
    }


def test_a_ros2_topic_has_its_frequency_and_is_watched_by_a_timeout(
    manager: ObserverManager, observations: Observations, peer: RosPeer
) -> None:
    writer = peer.publisher("lidar", "/scan", LaserScan)
    manager.add(frequency("/scan", [[]]))
    manager.add({"type": "timeout", "topics": [{"name": "scan", "timeout": 0.3}]})
    with streaming(writer, 40):
        found = observations.next(seen("frequency", ["scan"], 1))
        assert 30 < found["values"]["frequency"] < 50
        observations.next(seen("timeout", ["scan"], 0))
    observations.next(seen("timeout", ["scan"], TIMEOUT))


def test_node_names_are_caller_ids_and_a_group_of_one_node_counts_only_it(
    manager: ObserverManager, observations: Observations, peer: RosPeer
) -> None:
    lidar = peer.publisher("lidar", "/scan", LaserScan)
    other = peer.publisher("other", "/scan", LaserScan, namespace="/robot1")
    manager.add(frequency("scan", [[], ["lidar"], ["/robot1/other"]]))
    with streaming(lidar, 40), streaming(other, 10):
        both = observations.next(seen("frequency", ["scan"], 1, []))
        only_lidar = observations.next(seen("frequency", ["scan"], 1, ["lidar"]))
        only_other = observations.next(seen("frequency", ["scan"], 1, ["robot1/other"]))
    assert 40 < both["values"]["frequency"] < 60
    assert 30 < only_lidar["values"]["frequency"] < 50
    assert 7 < only_other["values"]["frequency"] < 13


def test_the_age_of_a_message_comes_from_its_header_stamp(
    manager: ObserverManager, observations: Observations, peer: RosPeer
) -> None:
    writer = peer.publisher("lidar", "/scan", LaserScan)
    manager.add(
        {
            "type": "timestamp",
            "main_loop_rate": 5.0,
            "topics": [
                {
                    "name": "/scan",
                    "filter": {"type": "mean", "window_size": 5},
                    "states": [
                        {
                            **OK,
                            "age": {"type": "in_between", "lower_bound": 0.4, "upper_bound": 0.6},
                        }
                    ],
                }
            ],
        }
    )
    with streaming(writer, 20, lambda: scan(time.time() - 0.5)):
        found = observations.next(seen("timestamp", ["scan"], 1))
    assert 0.4 < found["values"]["age"] < 0.6


def test_scores_read_any_field_of_a_ros2_message_by_its_path(
    manager: ObserverManager, observations: Observations, peer: RosPeer
) -> None:
    scans = peer.publisher("lidar", "/scan", LaserScan)
    battery = peer.publisher("battery_driver", "/battery", Float64)
    low = {"state": "low", "number": -2, "score": {"type": "less_than", "less_than": 20}}
    manager.add(
        {
            "type": "value",
            "main_loop_rate": 5.0,
            "topics": [
                {
                    "name": "scan",
                    "field": "ranges.1",
                    "filter": {"type": "mean", "window_size": 3},
                    "states": [{**OK, "score": {"type": "exact", "exact": 2.0}}],
                },
                {
                    "name": "battery",
                    "callerid": ["battery_driver"],
                    "filter": {"type": "mean", "window_size": 3},
                    "states": [low],
                },
            ],
        }
    )
    with streaming(scans, 20), streaming(battery, 20, lambda: Float64(data=12.5)):
        assert observations.next(seen("scores", ["scan"], 1))["values"]["score"] == 2.0
        drained = observations.next(seen("scores", ["battery"], -2, ["battery_driver"]))
    assert drained["values"]["score"] == 12.5


def test_timing_measures_the_delay_from_one_ros2_topic_to_another(
    manager: ObserverManager, observations: Observations, peer: RosPeer
) -> None:
    scans = peer.publisher("lidar", "/scan", LaserScan)
    filtered = peer.publisher("lidar_filter", "/scan_filtered", LaserScan, reliable=True)
    manager.add(
        {
            "type": "timing",
            "main_loop_rate": 5.0,
            "topics": [
                {
                    "topicA": "scan",
                    "topicB": "/scan_filtered",
                    "calleridB": ["lidar_filter"],
                    "filter": {"type": "mean", "window_size": 5},
                    "states": [
                        {
                            **OK,
                            "delay": {
                                "type": "in_between",
                                "lower_bound": 0.03,
                                "upper_bound": 0.12,
                            },
                        }
                    ],
                }
            ],
        }
    )
    stop = threading.Event()

    def answer_late() -> None:
        while not stop.is_set():
            scans.write(scan())
            stop.wait(0.06)
            filtered.write(scan())
            stop.wait(0.1)

    thread = threading.Thread(target=answer_late)
    thread.start()
    try:
        found = observations.next(seen("timing", ["scan", "scan_filtered"], 1))
    finally:
        stop.set()
        thread.join()
    assert 0.03 < found["values"]["delay"] < 0.12


def odometry(yaw_rate: float) -> Odometry:
    twist = Twist(linear=Vector3(x=0.3), angular=Vector3(z=yaw_rate))
    return Odometry(header=Header(stamp=stamp()), twist=TwistWithCovariance(twist=twist))


@pytest.mark.parametrize("source_b", ["imu", "twist"])
def test_movement_compares_odometry_with_an_imu_or_a_commanded_twist(
    manager: ObserverManager, observations: Observations, peer: RosPeer, source_b: str
) -> None:
    odom = peer.publisher("robot_base", "/odom", Odometry)
    if source_b == "imu":
        other = peer.publisher("imu_driver", "/imu", Imu)
        topic, make = "imu", lambda: Imu(angular_velocity=Vector3(z=0.5))
    else:
        other = peer.publisher("teleop", "/cmd_vel", Twist)
        topic, make = "cmd_vel", lambda: Twist(angular=Vector3(z=0.5))
    grip = {**OK, "state": "grip", "rot_z": {"type": "gauss", "mean": 0.0, "std_deviation": 0.1}}
    manager.add(
        {
            "type": "movement",
            "main_loop_rate": 5.0,
            "correlations": [
                {
                    "source_A": {"topic": "odom", "type": "odometry"},
                    "source_B": {"topic": topic, "type": source_b},
                    "rot_z_filter": {"type": "mean", "window_size": 5},
                    "states": [grip],
                }
            ],
        }
    )
    with streaming(odom, 20, lambda: odometry(0.5)), streaming(other, 20, make):
        found = observations.next(seen("movement", ["odom", topic], 1))
        assert abs(found["values"]["rot_z"]) < 1e-9
    with streaming(odom, 20, lambda: odometry(0.1)), streaming(other, 20, make):
        slip = observations.next(seen("movement", ["odom", topic], -2))
    assert slip["values"]["rot_z"] < -0.1


def test_a_topic_without_a_declared_type_is_read_as_its_publisher_types_it(
    manager: ObserverManager, observations: Observations, peer: RosPeer, link: Ros2Link
) -> None:
    manager.add(frequency("mystery", [["sensor"]]))
    assert link.topics.status()["/mystery"] == {
        "type": None,
        "reading": False,
        "handlers": 1,
        "malformed": 0,
    }
    writer = peer.publisher("sensor", "/mystery", LaserScan)
    assert wait_for(lambda: link.topics.status()["/mystery"]["reading"])
    assert link.topics.status()["/mystery"]["type"] == "sensor_msgs/msg/LaserScan"
    with streaming(writer, 20):
        observations.next(seen("frequency", ["mystery"], 1, ["sensor"]))


def test_a_type_nobody_defines_is_one_warning_and_nothing_else(
    manager: ObserverManager, peer: RosPeer, link: Ros2Link, caplog: pytest.LogCaptureFixture
) -> None:
    manager.add(frequency("mystery", [[]]))
    with caplog.at_level(logging.WARNING, logger="dura.ros2"):
        writer = peer.publisher("sensor", "/mystery", Thing)
        assert wait_for(lambda: any("custom_msgs/msg/Thing" in r.message for r in caplog.records))
        with streaming(writer, 50, lambda: Thing(value=1)):
            time.sleep(0.3)
    warnings = [r for r in caplog.records if r.name == "dura.ros2"]
    assert len(warnings) == 1 and "\n" not in warnings[0].getMessage()
    assert warnings[0].exc_info is None
    assert link.topics.status()["/mystery"]["reading"] is False


def test_a_malformed_sample_is_one_warning_and_the_topic_is_still_observed(
    manager: ObserverManager,
    observations: Observations,
    peer: RosPeer,
    caplog: pytest.LogCaptureFixture,
) -> None:
    writer = peer.publisher("lidar", "/scan", LaserScan)
    manager.add(frequency("scan", [["lidar"]]))
    positive = {**OK, "score": {"type": "greater_than", "greater_than": 0}}
    scores = {"name": "scan", "field": "ranges.0", "states": [positive]}
    filtered = {**scores, "filter": {"type": "mean", "window_size": 2}}
    manager.add({"type": "scores", "main_loop_rate": 5.0, "topics": [filtered]})
    # Cyclone checks the CDR structure of what is written, not the text in strings
    garbage = scan().serialize().replace(b"laser\x00", b"\xffaser\x00")

    with caplog.at_level(logging.WARNING, logger="dura.ros2"), _raw(writer, garbage, 40):
        observations.next(seen("frequency", ["scan"], 1, ["lidar"]))
        no_value = observations.next(seen("scores", ["scan"], GENERAL_ERROR))
    assert "without a number at 'ranges.0'" in no_value["verbose_observation_msg"]
    warnings = [r for r in caplog.records if r.name == "dura.ros2"]
    assert warnings and "malformed sample #1 on ROS 2 topic /scan from lidar" in warnings[0].message
    assert all(r.exc_info is None and "\n" not in r.getMessage() for r in warnings)


class _raw:
    """Write raw bytes at a rate on a thread (a writer that does not speak CDR)."""

    def __init__(self, writer: Any, data: bytes, rate: float) -> None:
        self.writer, self.data, self.rate = writer, data, rate
        self.stop = threading.Event()
        self.thread = threading.Thread(target=self.run)

    def run(self) -> None:
        while not self.stop.is_set():
            ddspy_write(self.writer._ref, self.data)
            self.stop.wait(1.0 / self.rate)

    def __enter__(self) -> None:
        self.thread.start()

    def __exit__(self, *exc: object) -> None:
        self.stop.set()
        self.thread.join()
