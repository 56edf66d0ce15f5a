"""Calls the lift car to the place ``to`` and waits until it stands there (at most
``timeout`` seconds)."""

from __future__ import annotations

from typing import Any

from executive.sdk import Behavior, GoalFailed


class CallLift(Behavior):
    def on_configure(self, params: dict[str, Any], achievements: dict[str, Any]) -> None:
        self.timeout = self.param("timeout", 10.0)

    def on_start(self) -> None:
        self.watch("lift_state", timeout=self.param("input_timeout", 1.0))

    def execute(self, goal: dict[str, Any]) -> dict[str, Any]:
        to = goal.get("to")
        if not isinstance(to, str):
            raise GoalFailed("the goal has no 'to'")
        self.publish("lift_cmd", {"to": to})
        self.wait_until(lambda: self.latest.get("lift_state", {}).get("at") == to,
                        self.timeout, f"lift at {to}")  # fmt: skip
        return {"lift_at": to}


def main() -> None:
    CallLift.main()


if __name__ == "__main__":
    main()
