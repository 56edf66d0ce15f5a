"""A recording's messages as bus messages that count themselves when their payload
does not decode: in their bag's :class:`~executive.bus.undecodable.UndecodableMessages`,
once, however many observers read them (a replay reports them, never drops them
silently).

A dura recording's JSON messages are :class:`RecordedMessage`; ROS 2 messages (CDR)
are :class:`RecordedRosMessage`, decoded when read as live ones are. A message that
cannot even be decompressed (rosbag2's zstd per message) is counted as it is read,
and is still replayed for its times.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

from executive.bus.message import Message
from executive.ros2.message import Decode, RosMessage
from knowledge.errors import BusError

Count = Callable[[str], None]  # count one undecodable message of a topic, with the reason


@dataclass
class _Counted:
    """A recorded message's decoding, counted when it fails: put before the message
    class, whose ``payload`` it wraps."""

    on_undecodable: Count | None = field(default=None, kw_only=True, repr=False, compare=False)

    @property
    def payload(self) -> dict[str, Any]:
        try:
            payload: dict[str, Any] = super().payload  # type: ignore[misc]  # the message's
        except BusError as e:
            _count(self, e)
            raise
        return payload


@dataclass
class RecordedMessage(_Counted, Message):
    """A JSON message of a recording; ``on_undecodable`` counts it if it does not decode."""


@dataclass
class RecordedRosMessage(_Counted, RosMessage):
    """A ROS 2 message of a recording; ``on_undecodable`` counts it if it does not decode."""


def _count(message: _Counted, error: BusError) -> None:
    """Count a message that did not decode, once (its ``on_undecodable`` is gone after)."""
    count, message.on_undecodable = message.on_undecodable, None
    if count is not None:
        count(str(error))


def ros_message(
    key: str,
    data: bytes,
    caller: str,
    times: tuple[int | None, int],
    *,
    decode: Decode,
    on_undecodable: Count,
    unpack: Callable[[bytes], bytes] | None = None,
) -> RecordedRosMessage:
    """A recorded ROS 2 message (``times``: sent and received, in ns), decompressed with
    ``unpack`` if the bag compressed each message; one that does not decompress is
    counted now and fails when decoded."""
    sent, received = times
    if unpack is not None:
        try:
            data = unpack(data)
        except Exception as e:  # zstd fails in several ways on bytes that are not its own
            why = f"cannot decompress it ({type(e).__name__}: {e})"
            on_undecodable(why)
            return RecordedRosMessage.at_ns(key, data, caller, sent, received, decode=_failing(why))
    return RecordedRosMessage.at_ns(
        key, data, caller, sent, received, decode=decode, on_undecodable=on_undecodable
    )


def _failing(why: str) -> Decode:
    def decode(raw: bytes, caller: str) -> dict[str, Any]:
        raise BusError(f"cannot decode a message from {caller or '?'}: {why}")

    return decode
