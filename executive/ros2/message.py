"""A ROS 2 message as observers read it: decoded from CDR only when a field is read.

Live samples from DDS and messages read from a bag are the same to the observers: a
:class:`~executive.bus.session.Message` whose ``payload`` is the message as a dict
(decoded on first use by whoever delivered it: frequency and timeout observers never
pay for decoding) and whose ``stamp`` is ``header.stamp``, as on dura's own bus.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

from executive.bus.message import Message
from knowledge.errors import BusError

# Decode one message's bytes (its caller id names it in a warning); raises BusError.
Decode = Callable[[bytes, str], dict[str, Any]]


@dataclass
class RosMessage(Message):
    """A ROS 2 message; ``payload`` is decoded from its CDR bytes when first read."""

    decode: Decode | None = field(default=None, repr=False)
    type: str = ""  # its ROS 2 type (sensor_msgs/msg/LaserScan), where known: recordings

    @property
    def payload(self) -> dict[str, Any]:
        if self._payload is None:
            if self.decode is None:
                raise BusError(f"{self.key}: a ROS 2 message without its type")
            self._payload = self.decode(self.raw, self.caller_id)
        return self._payload

    @property
    def stamp(self) -> float | None:
        """Return ``header.stamp`` in seconds (a message without a header: its ``stamp``)."""
        stamp = self._stamp()
        if isinstance(stamp, tuple):
            return stamp[0] + stamp[1] * 1e-9
        return float(stamp) if isinstance(stamp, (int, float)) else None

    @property
    def stamp_ns(self) -> int | None:
        """Return ``header.stamp`` in integer nanoseconds, exact."""
        stamp = self._stamp()
        if isinstance(stamp, tuple):
            return stamp[0] * 1_000_000_000 + stamp[1]
        return round(stamp * 1e9) if isinstance(stamp, (int, float)) else None

    def _stamp(self) -> tuple[int, int] | float | None:
        """``header.stamp`` as (sec, nanosec), or a plain ``stamp`` number."""
        payload = self.payload
        header = payload.get("header")
        stamp = header.get("stamp") if isinstance(header, dict) else payload.get("stamp")
        if isinstance(stamp, dict):
            sec, nanosec = stamp.get("sec"), stamp.get("nanosec")
            if isinstance(sec, int) and isinstance(nanosec, int):
                return sec, nanosec
            return None
        return float(stamp) if isinstance(stamp, (int, float)) else None
