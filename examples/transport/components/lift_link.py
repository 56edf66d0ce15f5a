"""The link to the building's lift: ``lift_cmd`` ``{"to": place}`` sends the car there
(it takes ``travel`` seconds); ``lift_state`` tells where it is, five times a second.
The car is where the link last sent it (an achievement, kept while the link is down),
at first at the place ``at`` (default ``hall1``)."""

from __future__ import annotations

from typing import Any

from executive.sdk import Functionality, Message


class LiftLink(Functionality):
    def on_configure(self, params: dict[str, Any], achievements: dict[str, Any]) -> None:
        self.travel = self.param("travel", 2.0)
        self.at: str | None = achievements.get("at") or self.param("at", "hall1")
        self.target: str | None = None
        self.arrives = 0.0

    def on_start(self) -> None:
        self.subscribe("lift_cmd", self.call)
        self.at_rate(5.0, self.report)

    def call(self, message: Message) -> None:
        to = message.payload.get("to")
        if isinstance(to, str) and to != (self.target or self.at):
            self.at, self.target = None, to
            self.arrives = self.clock.monotonic() + self.travel
            self.achieve("at", to)  # the car gets there, with the link or without it

    def report(self) -> None:
        if self.target is not None and self.clock.monotonic() >= self.arrives:
            self.at, self.target = self.target, None
        self.publish("lift_state", {"at": self.at, "moving": self.target is not None})


def main() -> None:
    LiftLink.main()


if __name__ == "__main__":
    main()
