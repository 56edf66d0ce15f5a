"""Pick and drop: close or open the gripper on a crate and wait until it has."""

from __future__ import annotations

from typing import Any, ClassVar

from executive.sdk import Behavior, GoalFailed


class GripAction(Behavior):
    close: ClassVar[bool]

    def on_configure(self, params: dict[str, Any], achievements: dict[str, Any]) -> None:
        self.timeout = self.param("timeout", 5.0)

    def on_start(self) -> None:
        self.watch("grip_state", "pose", timeout=self.param("input_timeout", 1.0))

    def execute(self, goal: dict[str, Any]) -> dict[str, Any]:
        crate, place = goal.get("crate"), goal.get("place")
        if not isinstance(crate, str) or not isinstance(place, str):
            raise GoalFailed("the goal needs 'crate' and 'place'")
        self.publish("grip_cmd", {"close": self.close})
        state = "closed" if self.close else "open"
        self.wait_until(lambda: self.latest.get("grip_state", {}).get("closed") is self.close,
                        self.timeout, f"gripper {state}")  # fmt: skip
        return {"crate": crate, "place": place, "holding": self.close}
