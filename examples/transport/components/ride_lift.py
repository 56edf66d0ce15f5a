"""Rides the lift from ``from`` to ``to``: drives into the car, sends it to the other
floor, waits until it arrives and drives out. Not interruptible: a robot never stops
between floors."""

from __future__ import annotations

from typing import Any

from executive.sdk import Behavior, GoalFailed


class RideLift(Behavior):
    def on_configure(self, params: dict[str, Any], achievements: dict[str, Any]) -> None:
        self.timeout = self.param("timeout", 10.0)
        self.drive = self.param("drive", 0.8)  # seconds into the car, and out again

    def on_start(self) -> None:
        timeout = self.param("input_timeout", 1.0)
        self.watch("lift_state", "pose", timeout=timeout)

    def lift_at(self, place: str) -> bool:
        return self.latest.get("lift_state", {}).get("at") == place

    def execute(self, goal: dict[str, Any]) -> dict[str, Any]:
        start, to = goal.get("from"), goal.get("to")
        if not isinstance(start, str) or not isinstance(to, str):
            raise GoalFailed("the goal needs 'from' and 'to'")
        self.wait_until(lambda: self.lift_at(start), self.timeout, f"lift at {start}")
        forward = {"linear": 0.5, "angular": 0.0}
        self.work_for(self.drive, lambda d: self.publish("cmd_vel", forward), job=f"into {start}")
        self.publish("lift_cmd", {"to": to})
        self.wait_until(lambda: self.lift_at(to), self.timeout, f"lift at {to}")
        self.work_for(self.drive, lambda d: self.publish("cmd_vel", forward), job=f"out at {to}")
        self.publish("cmd_vel", {"linear": 0.0, "angular": 0.0})
        return {"at": to}


def main() -> None:
    RideLift.main()


if __name__ == "__main__":
    main()
