"""A simulated photographer: after ``duration`` seconds, returns the newest ``image``.

The goal times out (a fault) when no image newer than the goal came within
``image_timeout`` seconds.
"""

from __future__ import annotations

from typing import Any

from executive.sdk import Behavior, GoalTimedOut, Message

POLL = 0.05


class TakePicture(Behavior):
    def on_configure(self, params: dict[str, Any], achievements: dict[str, Any]) -> None:
        self.duration = self.param("duration", 1.0)
        self.image_timeout = self.param("image_timeout", 2.0)
        self.latest: tuple[float, dict[str, Any]] | None = None

    def on_start(self) -> None:
        self.subscribe("image", self.see)

    def see(self, message: Message) -> None:
        self.latest = (self.clock.monotonic(), message.payload)

    def execute(self, goal: dict[str, Any]) -> dict[str, Any]:
        began = self.clock.monotonic()
        self.sleep(self.duration)
        while self.latest is None or self.latest[0] < began:
            if self.clock.monotonic() - began > self.duration + self.image_timeout:
                raise GoalTimedOut(f"no image within {self.image_timeout:g} s")
            self.sleep(POLL)
        image = self.latest[1]
        return {
            "place": goal.get("place"),
            "image_seq": image.get("seq"),
            "brightness": image.get("brightness"),
            "image_stamp": image.get("stamp"),
        }


def main() -> None:
    TakePicture.main()


if __name__ == "__main__":
    main()
