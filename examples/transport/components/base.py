"""A simulated base with a battery: follows ``cmd_vel``, publishes ``odom`` at ``rate``
Hz and ``battery`` once a second.

The battery drains by ``drain`` percent per second of driving (and ``idle_drain`` at
rest) and charges by ``charge_rate`` percent per second while a ``charge`` message
says so (the docking station). The level starts at ``battery`` percent and is kept as
an achievement while the base is switched off. The robot description's sensing rule
turns a low level into ``(battery_low)``; the integrity goals take it from there.
"""

from __future__ import annotations

from typing import Any

from executive.sdk import Functionality, Message


class Base(Functionality):
    def on_configure(self, params: dict[str, Any], achievements: dict[str, Any]) -> None:
        self.rate = self.param("rate", 20.0)
        self.level = float(achievements.get("battery", self.param("battery", 100.0)))
        self.drain = self.param("drain", 0.5)
        self.idle_drain = self.param("idle_drain", 0.0)
        self.charge_rate = self.param("charge_rate", 10.0)
        self.x = 0.0
        self.linear = 0.0
        self.commanded = self.charging_until = 0.0

    def on_start(self) -> None:
        self.subscribe("cmd_vel", self.command)
        self.subscribe("charge", self.charge)
        self.at_rate(self.rate, self.step)
        self.at_rate(1.0, self.report)

    def command(self, message: Message) -> None:
        linear = message.payload.get("linear", 0.0)
        if isinstance(linear, (int, float)):
            self.linear, self.commanded = float(linear), self.clock.monotonic()

    def charge(self, message: Message) -> None:
        on = message.payload.get("on") is True
        self.charging_until = self.clock.monotonic() + 1.0 if on else 0.0

    def step(self) -> None:
        now, dt = self.clock.monotonic(), 1.0 / self.rate
        if now - self.commanded > 0.5:  # a command holds for half a second
            self.linear = 0.0
        self.x += self.linear * dt
        if now < self.charging_until:
            self.level = min(100.0, self.level + self.charge_rate * dt)
        else:
            self.level -= (self.drain if self.linear else self.idle_drain) * dt
            self.level = max(0.0, self.level)
        self.publish("odom", {"x": self.x, "y": 0.0, "theta": 0.0, "linear": self.linear})

    def report(self) -> None:
        self.publish("battery", {"level": round(self.level, 2)})
        self.achieve("battery", round(self.level, 2))


def main() -> None:
    Base.main()


if __name__ == "__main__":
    main()
