"""A stand-in navigator, a managed node like Nav2's: ``/navigator`` serves the action
``/navigate_to_pose`` (``nav2_msgs/action/NavigateToPose``) while it is active.

It subscribes to ``/scan`` and ``/odom`` and drives (``/cmd_vel``) from where the
odometry says the robot is straight to the goal's position at ``speed`` m/s, with
feedback ten times a second. Without a scan it
stops and waits (a recovery, counted in the feedback); after ``scan_timeout`` s
without one (counted from the goal's start if none came yet) it aborts the goal. A goal farther than 100 m from the origin is outside
the map: aborted at once. A goal is cancelled when asked, and when the node is
deactivated.

Parameters (``DURA_PARAMS``): ``speed`` (default 1.0), ``scan_timeout`` (default 8),
``fail_configure: true`` (its configure transition fails, as with a missing map).
"""

from __future__ import annotations

import math
import threading
import time
from typing import Any

from . import interfaces as ros
from .action_server import ABORTED, CANCELED, SUCCEEDED, ActionServer, GoalHandle, action_types
from .lifecycle_node import LifecycleNode
from .rosnode import params

UNKNOWN, TIMEOUT = 9000, 9003  # NavigateToPose's error codes
SCAN_GAP = 0.5  # seconds without a scan before it stops and waits
ARRIVED = 0.05  # metres from the goal that count as there


class Navigator(LifecycleNode):
    def __init__(
        self,
        domain_id: int | None = None,
        *,
        speed: float = 1.0,
        scan_timeout: float = 8.0,
        fail_configure: bool = False,
    ) -> None:
        super().__init__("navigator", domain_id=domain_id)
        self.speed, self.scan_timeout, self.fail_configure = speed, scan_timeout, fail_configure
        self.position: ros.Point | None = None  # from /odom
        self.last_scan = 0.0
        self.busy = threading.Lock()  # one goal at a time
        self.cmd_vel = self.publisher("/cmd_vel", ros.Twist)
        self.subscription("/scan", ros.LaserScan, self._scan, reliable=False)
        self.subscription("/odom", ros.Odometry, self._odom)
        types = action_types(ros, "NavigateToPose")
        self.server = ActionServer(
            self, "/navigate_to_pose", types, accept=self._accept, execute=self._navigate
        )

    def on_configure(self) -> bool:
        return not self.fail_configure

    def on_deactivate(self) -> bool:
        for handle in list(self.server.goals.values()):
            handle.cancel_requested.set()  # an inactive navigator drives nowhere
        return True

    def _scan(self, scan: Any) -> None:
        self.last_scan = time.monotonic()

    def _odom(self, odom: Any) -> None:
        self.position = odom.pose.pose.position

    def _accept(self, goal: Any) -> bool:
        return self.active and not self.busy.locked()

    def _navigate(self, handle: GoalHandle) -> tuple[int, Any]:
        with self.busy:
            return self._drive(handle)

    def _drive(self, handle: GoalHandle) -> tuple[int, Any]:
        target = handle.goal.pose.pose.position
        if math.hypot(target.x, target.y) > 100.0:
            return ABORTED, ros.NavigateToPose_Result(
                error_code=UNKNOWN, error_msg="outside the map"
            )
        began, recoveries, waiting = time.monotonic(), 0, False
        step = 0.1
        while self.position is None and time.monotonic() - began < 2.0:
            time.sleep(step)
        while True:
            if handle.cancel_requested.is_set():
                self.cmd_vel.write(ros.Twist())
                return CANCELED, ros.NavigateToPose_Result()
            silent = time.monotonic() - max(self.last_scan, began)  # none yet: since the goal
            if silent > self.scan_timeout:
                self.cmd_vel.write(ros.Twist())
                return ABORTED, ros.NavigateToPose_Result(
                    error_code=TIMEOUT, error_msg=f"no scan for {silent:.1f} s"
                )
            here = self.position or ros.Point()
            dx, dy = target.x - here.x, target.y - here.y
            left = math.hypot(dx, dy)
            if left < ARRIVED:
                self.cmd_vel.write(ros.Twist())
                return SUCCEEDED, ros.NavigateToPose_Result()
            if silent > SCAN_GAP:  # blind: stop and wait for the scan to come back
                recoveries += 0 if waiting else 1
                waiting = True
                velocity = ros.Twist()
            else:
                waiting = False
                speed = min(self.speed, left / step)
                velocity = ros.Twist(linear=ros.Vector3(x=dx / left * speed, y=dy / left * speed))
            self.cmd_vel.write(velocity)
            elapsed = time.monotonic() - began
            remaining = left / self.speed
            handle.publish_feedback(ros.NavigateToPose_Feedback(
                current_pose=ros.PoseStamped(pose=ros.Pose(position=here)),
                navigation_time=ros.Duration(sec=int(elapsed), nanosec=int(elapsed % 1 * 1e9)),
                estimated_time_remaining=ros.Duration(sec=int(remaining),
                                                      nanosec=int(remaining % 1 * 1e9)),
                number_of_recoveries=recoveries, distance_remaining=left,
            ))  # fmt: skip
            time.sleep(step)


def main() -> None:
    p = params()
    Navigator(
        speed=float(p.get("speed", 1.0)),
        scan_timeout=float(p.get("scan_timeout", 8.0)),
        fail_configure=bool(p.get("fail_configure", False)),
    ).run_until_stopped()


if __name__ == "__main__":
    main()
