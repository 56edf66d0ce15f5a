"""A simulated move: drives toward ``target`` for ``duration`` seconds of running time.

Needs ``scan_filtered`` and ``odom``: the goal fails when either has been silent for
``input_timeout`` seconds (counted from the goal's start and from every resume). It
publishes ``cmd_vel`` and its progress as feedback, and stores the progress as an
achievement, so that a restarted move_to with the same target goes on where it was.
"""

from __future__ import annotations

import time
from typing import Any

from executive.bus import Message
from executive.component import Behavior, GoalFailed

INPUTS = ("scan_filtered", "odom")
ACHIEVE_EVERY = 10  # steps between stored achievements


class MoveTo(Behavior):
    def on_configure(self, params: dict[str, Any], achievements: dict[str, Any]) -> None:
        self.duration = self.param("duration", 5.0)
        self.rate = self.param("rate", 10.0)
        self.speed = self.param("speed", 0.5)
        self.input_timeout = self.param("input_timeout", 1.0)
        self.heard: dict[str, float] = {}
        self.fresh_since = time.monotonic()

    def on_start(self) -> None:
        for topic in INPUTS:
            self.subscribe(topic, self.hear)

    def on_resume(self) -> None:
        self.fresh_since = time.monotonic()

    def hear(self, message: Message) -> None:
        self.heard[message.key.removeprefix("topic/")] = time.monotonic()

    def check_inputs(self) -> None:
        now = time.monotonic()
        for topic in INPUTS:
            silent = now - max(self.heard.get(topic, 0.0), self.fresh_since)
            if silent > self.input_timeout:
                raise GoalFailed(f"no {topic} for {silent:.1f} s")

    def execute(self, goal: dict[str, Any]) -> dict[str, Any]:
        target = goal.get("target")
        if target is None:
            raise GoalFailed("the goal has no 'target'")
        stored = self.achievements.get("progress")
        done = 0.0
        if isinstance(stored, dict) and stored.get("target") == target:
            done = float(stored.get("done", 0.0))
            self.log.info("warm start toward %s at %.0f%%", target, done * 100)
        self.fresh_since = time.monotonic()
        period = 1.0 / self.rate
        step = 0
        while done < 1.0:
            self.sleep(period)
            self.check_inputs()
            done = min(1.0, done + period / self.duration)
            step += 1
            self.publish("cmd_vel", {"linear": self.speed, "angular": 0.0})
            self.feedback(target=target, done=round(done, 3))
            if step % ACHIEVE_EVERY == 0:
                self.achieve("progress", {"target": target, "done": done})
        self.publish("cmd_vel", {"linear": 0.0, "angular": 0.0})
        return {"target": target, "reached": True}


def main() -> None:
    MoveTo.main()


if __name__ == "__main__":
    main()
