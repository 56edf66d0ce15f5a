"""A simulated move: drives toward ``target`` for ``duration`` seconds of running time.

Needs ``scan_filtered`` and ``odom``: the goal fails when either has been silent for
``input_timeout`` seconds (counted from the goal's start and from every resume). It
publishes ``cmd_vel`` and its progress as feedback, and stores the progress as an
achievement, so that a restarted move_to with the same target goes on where it was.
"""

from __future__ import annotations

from typing import Any

from executive.sdk import Behavior, GoalFailed

INPUTS = ("scan_filtered", "odom")


class MoveTo(Behavior):
    def on_configure(self, params: dict[str, Any], achievements: dict[str, Any]) -> None:
        self.duration = self.param("duration", 5.0)
        self.rate = self.param("rate", 10.0)
        self.speed = self.param("speed", 0.5)
        self.input_timeout = self.param("input_timeout", 1.0)

    def on_start(self) -> None:
        self.watch(*INPUTS, timeout=self.input_timeout)

    def execute(self, goal: dict[str, Any]) -> dict[str, Any]:
        target = goal.get("target")
        if target is None:
            raise GoalFailed("the goal has no 'target'")
        drive = {"linear": self.speed, "angular": 0.0}
        self.work_for(
            self.duration, lambda done: self.publish("cmd_vel", drive),
            job=f"move to {target}", rate=self.rate,
        )  # fmt: skip
        self.publish("cmd_vel", {"linear": 0.0, "angular": 0.0})
        return {"target": target, "reached": True}


def main() -> None:
    MoveTo.main()


if __name__ == "__main__":
    main()
