"""Observers measure robot time: with ``DURA_TIME_SCALE=N`` what they see runs N times
faster, like the components they watch.

The observer manager hands every observer its loop times and messages through a
:class:`RobotTime`: the ``now`` of a loop, the ``received`` and ``sent`` times and the
``stamp`` of each message are wall-clock epoch seconds multiplied by the scale, so
differences between them are robot seconds. A lidar publishing at 10 Hz of robot time
(100 Hz on the wall clock at N = 10) is measured at 10 Hz, its silence in robot seconds,
and an observer's ``main_loop_rate`` and ``start_up_time`` are robot time too. Without a
scale messages pass unchanged.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

from executive.bus.clock import Clock
from executive.bus.message import Message


@dataclass
class ScaledMessage(Message):
    """A message seen on the robot-time axis; its payload is the original's."""

    original: Message | None = field(default=None, repr=False)
    scale: float = 1.0

    @property
    def payload(self) -> dict[str, Any]:
        return self.original.payload if self.original is not None else super().payload

    @property
    def stamp(self) -> float | None:
        stamp = self.original.stamp if self.original is not None else None
        return None if stamp is None else stamp * self.scale

    @property
    def stamp_ns(self) -> int | None:
        stamp = self.original.stamp_ns if self.original is not None else None
        return None if stamp is None else round(stamp * self.scale)


class RobotTime:
    """The time axis observers see (see the module docstring)."""

    def __init__(self, clock: Clock) -> None:
        self.clock = clock

    def now(self) -> float:
        """Return now, on the robot-time axis."""
        return time.time() * self.clock.scale

    def now_ns(self) -> int:
        """Return now in integer nanoseconds, on the robot-time axis."""
        scale = self.clock.scale
        return time.time_ns() if scale == 1.0 else round(time.time_ns() * scale)

    def message(self, message: Message) -> Message:
        """Return a message as seen on the robot-time axis."""
        scale = self.clock.scale
        if scale == 1.0:
            return message
        sent = message.sent_ns
        return ScaledMessage.at_ns(
            message.key, message.raw, message.caller_id,
            None if sent is None else round(sent * scale), round(message.received_ns * scale),
            original=message, scale=scale,
        )  # fmt: skip

    def handler(self, handler: Callable[[Message], None]) -> Callable[[Message], None]:
        """Wrap a handler so that it gets messages on the robot-time axis."""
        if not self.clock.scaled:
            return handler
        return lambda message: handler(self.message(message))
