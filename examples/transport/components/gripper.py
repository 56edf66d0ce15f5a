"""A simulated gripper: ``grip_cmd`` ``{"close": bool}`` closes or opens it within
``actuation`` seconds; ``grip_state`` ``{"closed": bool}`` five times a second. A
gripper that is switched off holds what it holds (the state is an achievement)."""

from __future__ import annotations

from typing import Any

from executive.sdk import Functionality, Message


class Gripper(Functionality):
    def on_configure(self, params: dict[str, Any], achievements: dict[str, Any]) -> None:
        self.actuation = self.param("actuation", 0.5)
        self.closed = self.wanted = achievements.get("closed") is True
        self.done_at = 0.0

    def on_start(self) -> None:
        self.subscribe("grip_cmd", self.command)
        self.at_rate(5.0, self.report)

    def command(self, message: Message) -> None:
        close = message.payload.get("close")
        if isinstance(close, bool) and close != self.wanted:
            self.wanted, self.done_at = close, self.clock.monotonic() + self.actuation
            self.achieve("closed", close)

    def report(self) -> None:
        if self.clock.monotonic() >= self.done_at:
            self.closed = self.wanted
        self.publish("grip_state", {"closed": self.closed})


def main() -> None:
    Gripper.main()


if __name__ == "__main__":
    main()
