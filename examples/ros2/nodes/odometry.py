"""A stand-in odometry source: node ``/odometry`` integrates ``/cmd_vel`` and publishes
``nav_msgs/Odometry`` on ``/odom``; its service ``/odometry/reset``
(``std_srvs/srv/Trigger``) relocalizes the robot.

Parameters (``DURA_PARAMS``): ``rate`` (Hz, default 20); ``lost: true`` makes every
reset fail (``success: false``), as when the robot cannot match the map; ``pose_file``
(default ``.dura/patrol-pose.json`` in the working folder) keeps the robot's position
while the node is restarted: the robot does not move when its odometry restarts.
"""

from __future__ import annotations

import json
import threading
import time
from pathlib import Path
from typing import Any

from . import interfaces as ros
from .rosnode import Node, now, params

POSE_FILE = ".dura/patrol-pose.json"


class Odometry(Node):
    def __init__(
        self,
        domain_id: int | None = None,
        rate: float = 20.0,
        lost: bool = False,
        pose_file: Path | None = None,
    ) -> None:
        super().__init__("odometry", domain_id=domain_id)
        self.rate, self.lost, self.pose_file = rate, lost, pose_file
        self.x = self.y = 0.0
        if pose_file is not None and pose_file.is_file():
            with_pose = json.loads(pose_file.read_text())
            self.x, self.y = float(with_pose["x"]), float(with_pose["y"])
        self.velocity = ros.Twist()
        self._lock = threading.Lock()
        self.odom = self.publisher("/odom", ros.Odometry)
        self.subscription("/cmd_vel", ros.Twist, self._command)
        self.service("/odometry/reset", ros.Trigger_Request, ros.Trigger_Response, self.reset)
        self._loop = threading.Thread(target=self._publish, daemon=True, name="odom")

    def start(self) -> None:
        super().start()
        self._loop.start()

    def _command(self, twist: Any) -> None:
        with self._lock:
            self.velocity = twist

    def reset(self, request: Any) -> dict[str, Any]:
        if self.lost:
            return {"success": False, "message": "no match with the map"}
        return {"success": True, "message": f"relocalized at ({self.x:.2f}, {self.y:.2f})"}

    def _keep(self) -> None:
        if self.pose_file is not None:
            self.pose_file.parent.mkdir(parents=True, exist_ok=True)
            self.pose_file.write_text(json.dumps({"x": self.x, "y": self.y}))

    def _publish(self) -> None:
        period = 1.0 / self.rate
        last = time.monotonic()
        while not self._stop.wait(period):
            tick = time.monotonic()
            with self._lock:
                v = self.velocity
            if v.linear.x or v.linear.y:
                self.x += v.linear.x * (tick - last)
                self.y += v.linear.y * (tick - last)
                self._keep()
            last = tick
            self.odom.write(ros.Odometry(
                header=ros.Header(stamp=now(), frame_id="odom"), child_frame_id="base_link",
                pose=ros.PoseWithCovariance(pose=ros.Pose(position=ros.Point(x=self.x, y=self.y))),
                twist=ros.TwistWithCovariance(twist=v),
            ))  # fmt: skip


def main() -> None:
    p = params()
    Odometry(
        rate=float(p.get("rate", 20.0)),
        lost=bool(p.get("lost", False)),
        pose_file=Path(str(p.get("pose_file", POSE_FILE))),
    ).run_until_stopped()


if __name__ == "__main__":
    main()
