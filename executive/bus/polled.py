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
# a sender's least lag is the least of its messages of the last one or two such spans
# (ns): a sender's clock that steps back (a time service's correction) is believed again
# within two spans, and a message that waited in the queue does not count as slow
SPAN = 30_000_000_000


class _Lag:
    """A sender's least lags (no dataclass: the quick commands' bus must not import
    ``dataclasses``, whose ``inspect`` and ``copy`` cost them their start)."""

    __slots__ = ("before", "current", "since")

    def __init__(self, current: int, before: int | None, since: int) -> None:
        self.current = current  # the least lag of the current span
        self.before = before  # of the span before it
        self.since = since  # when the current span began (ns, this clock)

    def least(self) -> int:
        return self.current if self.before is None else min(self.current, self.before)


class SenderClocks:
    """Each sender's clock seen from here: the least lag of its recent messages (its
    clock's offset plus the transport's, as near as seen)."""

    def __init__(self) -> None:
        self._lags: dict[str, _Lag] = {}

    def arrival(self, sender: str, sent: int, taken: int) -> int:
        """When a message ``sent`` on its sender's clock and ``taken`` now (ns) arrived,
        as near as known: its sent time on this clock, at most ``taken``."""
        lag = taken - sent
        known = self._lags.get(sender)
        if known is None:
            if len(self._lags) >= SENDERS:
                del self._lags[next(iter(self._lags))]
            known = self._lags[sender] = _Lag(lag, None, taken)
        elif taken - known.since >= SPAN:  # a new span
            recent = taken - known.since < 2 * SPAN
            known.before, known.current, known.since = known.current if recent else None, lag, taken
        else:
            known.current = min(known.current, lag)
        return min(taken, sent + known.least())


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
