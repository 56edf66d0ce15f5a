"""The movement observer: wheel odometry and an IMU that stop agreeing when the robot slips."""

from __future__ import annotations

from typing import Any

from executive.bus.message import Message
from executive.bus.session import Bus
from executive.bus.states import Lifecycle
from monitoring.observer import Environment, make_observer
from monitoring.observer_config import config_of
from monitoring.observer_manager import ObserverManager
from tests.monitoring.harness import Observations, Publish, seen, set_state, stream

MOVEMENT: dict[str, Any] = {
    "type": "velocity",
    "main_loop_rate": 5.0,
    "correlations": [
        {
            "source_A": {"topic": "odom", "type": "odometry"},
            "source_B": {"topic": "imu", "type": "imu"},
            "rot_z_filter": {"type": "mean", "window_size": 10},
            "states": [
                {
                    "state": "grip",
                    "number": 1,
                    "rot_z": {"type": "gauss", "mean": 0.0, "std_deviation": 0.1},
                }
            ],
        }
    ],
}


def odom(yaw_rate: float) -> dict[str, Any]:
    return {"twist": {"linear": {"x": 0.3}, "angular": {"z": yaw_rate}}}


def imu(yaw_rate: float) -> dict[str, Any]:
    return {"angular_velocity": {"z": yaw_rate}, "linear_acceleration": {"x": 0.0}}


def test_slip_is_detected_and_blames_the_moving_behavior(
    manager: ObserverManager, observations: Observations, publish: Publish, bus: Bus
) -> None:
    publish(
        "robot_base",
        [
            stream("topic/odom", {"rate": 20, "payload": odom(0.5)}),
            stream(
                "topic/imu",
                {"rate": 20, "duration": 1.5, "payload": imu(0.5)},
                {"rate": 20, "payload": imu(0.1)},
            ),
        ],
    )
    manager.add(MOVEMENT, component="move_to")
    set_state(bus, "move_to", Lifecycle.READY)
    grip = observations.next(seen("movement", ["odom", "imu", "move_to"], 1))
    assert abs(grip["values"]["rot_z"]) <= 0.1
    slip = observations.next(seen("movement", ["odom", "imu", "move_to"], -2))
    assert slip["values"]["rot_z"] > 0.1


def test_only_fresh_pairs_are_compared_and_a_functionality_names_no_behavior() -> None:
    config = config_of(MOVEMENT)
    observer = make_observer(config, Environment(owner="robot_base"))
    observer.start(0.0)
    handlers = dict(observer.inputs())
    handlers["topic/odom"](
        Message("topic/odom", b'{"twist": {"angular": {"z": 1.0}}}', "b", None, 1.0)
    )
    handlers["topic/imu"](Message("topic/imu", b'{"angular_velocity": {"z": 0.0}}', "b", None, 2.0))
    assert observer.observe(2.5) == []  # 1 s apart: too old to compare
    handlers["topic/imu"](Message("topic/imu", b'{"angular_velocity": {"z": 0.9}}', "b", None, 2.1))
    handlers["topic/odom"](
        Message("topic/odom", b'{"twist": {"angular": {"z": 1.0}}}', "b", None, 2.2)
    )
    [result] = observer.observe(3.0)
    assert result.info.resource == ("odom", "imu")
    assert result.values["rot_z"] == 1.0 - 0.9
