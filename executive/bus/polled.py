"""A subscription whose messages wait in a queue until their taker drains it
(:meth:`executive.bus.session.Bus.poll`), with each message's arrival on the taker's
clock."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import zenoh

from executive.bus.message import Message

POLL_CAPACITY = 4096  # messages a polled subscription holds until drained
SENDERS = 1024  # senders whose clock offset is kept (the oldest is forgotten first)
# how fast a sender's least lag is forgotten (ns per ns since it was learnt: 10 ms a
# second), so that a sender's clock that steps back (a time service's correction) is
# believed again within minutes instead of making its messages look old for ever
FORGET = 0.01


class SenderClocks:
    """Each sender's clock seen from here: the least lag of its messages (its clock's
    offset plus the transport's), forgotten slowly."""

    def __init__(self) -> None:
        self._least: dict[str, tuple[int, int]] = {}  # sender -> (least lag, learnt at)

    def arrival(self, sender: str, sent: int, taken: int) -> int:
        """When a message ``sent`` on its sender's clock and ``taken`` now (ns) arrived,
        as near as known: its sent time on this clock, at most ``taken``."""
        known = self._least.get(sender)
        lag = taken - sent
        if known is None:
            if len(self._least) >= SENDERS:
                del self._least[next(iter(self._least))]
            least = lag
        else:
            least = min(known[0] + round((taken - known[1]) * FORGET), lag)
        self._least[sender] = (least, taken)
        return min(taken, sent + least)


class Polled:
    """A subscription whose messages wait until taken (see
    :meth:`executive.bus.session.Bus.poll`)."""

    def __init__(
        self,
        subscriber: Any,
        message: Callable[[zenoh.Sample], Message | None],
        clocks: SenderClocks,
    ) -> None:
        self._subscriber = subscriber
        self._message = message
        self._clocks = clocks  # shared by the session's polled keys

    def drain(self) -> list[Message]:
        """Take every message that has arrived, oldest first."""
        messages: list[Message] = []
        while (sample := self._subscriber.try_recv()) is not None:
            message = self._message(sample)
            if message is not None:
                messages.append(self._arrival(message))
        return messages

    def _arrival(self, message: Message) -> Message:
        """The message with its ``received`` time when it arrived, as near as known: its
        sent time on this clock, which is at most when it was taken. The least lag seen
        from its sender (the transport's, plus the offset of the sender's clock) maps the
        sender's clock onto this one (see :class:`SenderClocks`)."""
        sent = message.sent_ns
        if sent is None:
            return message
        arrived = self._clocks.arrival(message.caller_id, sent, message.received_ns)
        return Message.at_ns(message.key, message.raw, message.caller_id, sent, arrived)

    def undeclare(self) -> None:
        self._subscriber.undeclare()
