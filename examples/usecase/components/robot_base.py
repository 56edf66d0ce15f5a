"""A simulated robot base: follows ``cmd_vel``, publishes ``odom`` and ``imu`` at ``rate`` Hz.

A velocity command holds for ``cmd_timeout`` seconds (default 0.5); then the base stops.
Under the ``slip`` fault the wheels spin: odometry reports ``slip_speed`` m/s more than
the IMU measures.
"""

from __future__ import annotations

import math
from typing import Any

from executive.sdk import FaultMode, Functionality, Message

OUT_OF_RANGE_SPEED = 1000.0  # m/s: no base drives this fast


class RobotBase(Functionality):
    def on_configure(self, params: dict[str, Any], achievements: dict[str, Any]) -> None:
        self.rate = self.param("rate", 20.0)
        self.cmd_timeout = self.param("cmd_timeout", 0.5)
        self.slip_speed = self.param("slip_speed", 0.5)
        self.x = self.y = self.theta = 0.0
        self.linear = self.angular = 0.0
        self.commanded = 0.0

    def on_start(self) -> None:
        self.subscribe("cmd_vel", self.command)
        self.at_rate(self.rate, self.step)

    def command(self, message: Message) -> None:
        linear, angular = message.payload.get("linear", 0.0), message.payload.get("angular", 0.0)
        if isinstance(linear, (int, float)) and isinstance(angular, (int, float)):
            self.linear, self.angular = float(linear), float(angular)
            self.commanded = self.clock.monotonic()

    def step(self) -> None:
        if self.clock.monotonic() - self.commanded > self.cmd_timeout:
            self.linear = self.angular = 0.0
        dt = 1.0 / self.rate
        previous = self.linear
        self.theta += self.angular * dt
        self.x += self.linear * math.cos(self.theta) * dt
        self.y += self.linear * math.sin(self.theta) * dt
        wheels = self.linear
        if self.faults.active(FaultMode.SLIP):
            wheels += self.slip_speed
        if self.faults.active(FaultMode.OUT_OF_RANGE):
            wheels = OUT_OF_RANGE_SPEED
        self.publish(
            "odom",
            {
                "x": self.x,
                "y": self.y,
                "theta": self.theta,
                "linear": wheels,
                "angular": self.angular,
            },
        )
        self.publish(
            "imu",
            {
                "linear_velocity": self.linear,
                "linear_acceleration": (self.linear - previous) / dt,
                "angular_velocity": self.angular,
            },
        )


def main() -> None:
    RobotBase.main()


if __name__ == "__main__":
    main()
