"""A scripted behavior for SDK tests: it watches ``water`` and brews with it.

A goal ``{}`` returns the water's temperature; ``{"world": "why"}`` raises GoalFailed
(impossible in the world); ``{"bug": True}`` raises a KeyError (a fault). Parameter:
``timeout`` (seconds the water may be silent, 2).
"""

from __future__ import annotations

from typing import Any

from executive.sdk import Behavior, GoalFailed


class Brewer(Behavior):
    def on_configure(self, params: dict[str, Any], achievements: dict[str, Any]) -> None:
        self.timeout = self.param("timeout", 2.0)

    def on_start(self) -> None:
        self.watch("water", timeout=self.timeout)

    def execute(self, goal: dict[str, Any]) -> dict[str, Any]:
        if "world" in goal:
            raise GoalFailed(goal["world"])
        if goal.get("bug"):
            return {"oops": goal["no such key"]}
        return {"celsius": self.latest["water"]["celsius"]}


if __name__ == "__main__":
    Brewer.main()
