"""Drives from ``start`` to ``target`` on one floor in ``duration`` seconds of running
time, on the ``pose`` from localization; a warm start after a restart goes on where it
was. Fails when the pose has been silent for ``input_timeout`` seconds."""

from __future__ import annotations

from typing import Any

from executive.sdk import Behavior, GoalFailed


class DriveTo(Behavior):
    def on_configure(self, params: dict[str, Any], achievements: dict[str, Any]) -> None:
        self.duration = self.param("duration", 4.0)
        self.speed = self.param("speed", 0.8)

    def on_start(self) -> None:
        self.watch("pose", timeout=self.param("input_timeout", 1.0))

    def execute(self, goal: dict[str, Any]) -> dict[str, Any]:
        target = goal.get("target")
        if not isinstance(target, str):
            raise GoalFailed("the goal has no 'target'")
        drive = {"linear": self.speed, "angular": 0.0}
        self.work_for(
            self.duration, lambda done: self.publish("cmd_vel", drive), job=f"drive to {target}"
        )
        self.publish("cmd_vel", {"linear": 0.0, "angular": 0.0})
        return {"at": target, "pose": self.latest.get("pose", {})}


def main() -> None:
    DriveTo.main()


if __name__ == "__main__":
    main()
