"""Localization: a ``pose`` for every ``scan``, where the odometry says the robot is.

No scan, no pose: when the lidar stops, so does the pose, and whatever drives on it
notices.
"""

from __future__ import annotations

from typing import Any

from executive.sdk import Functionality, Message


class Localization(Functionality):
    def on_configure(self, params: dict[str, Any], achievements: dict[str, Any]) -> None:
        self.odom: dict[str, Any] = {"x": 0.0, "y": 0.0, "theta": 0.0}

    def on_start(self) -> None:
        self.subscribe("odom", self.moved)
        self.subscribe("scan", self.locate)

    def moved(self, message: Message) -> None:
        self.odom = message.payload

    def locate(self, message: Message) -> None:
        pose = {key: float(self.odom.get(key, 0.0)) for key in ("x", "y", "theta")}
        self.publish("pose", {**pose, "scan_seq": message.payload.get("seq")})


def main() -> None:
    Localization.main()


if __name__ == "__main__":
    main()
