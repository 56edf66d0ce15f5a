"""Docks at the station (``approach`` seconds of driving) and charges until the battery
reports ``full`` percent (at most ``timeout`` seconds), then undocks."""

from __future__ import annotations

from typing import Any

from executive.sdk import Behavior, GoalFailed


class DockAndCharge(Behavior):
    def on_configure(self, params: dict[str, Any], achievements: dict[str, Any]) -> None:
        self.approach = self.param("approach", 1.0)
        self.full = self.param("full", 90.0)
        self.timeout = self.param("timeout", 8.0)

    def on_start(self) -> None:
        self.watch("battery", "pose", timeout=self.param("input_timeout", 2.0))

    def level(self) -> float:
        return float(self.latest.get("battery", {}).get("level", 0.0))

    def charged(self) -> bool:
        self.publish("charge", {"on": True})
        return self.level() >= self.full

    def execute(self, goal: dict[str, Any]) -> dict[str, Any]:
        dock = goal.get("dock")
        if not isinstance(dock, str):
            raise GoalFailed("the goal has no 'dock'")
        slow = {"linear": 0.2, "angular": 0.0}
        self.work_for(self.approach, lambda d: self.publish("cmd_vel", slow), job=f"dock {dock}")
        self.publish("cmd_vel", {"linear": 0.0, "angular": 0.0})
        try:
            self.wait_until(self.charged, self.timeout, f"battery at {self.full:g} %")
        finally:
            self.publish("charge", {"on": False})
        return {"dock": dock, "battery": self.level()}


def main() -> None:
    DockAndCharge.main()


if __name__ == "__main__":
    main()
