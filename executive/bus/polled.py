"""A subscription whose messages wait in a queue until their taker drains it
(:meth:`executive.bus.session.Bus.poll`), with each message's arrival on the taker's
clock.

Two subscriptions of the key make one :class:`Polled`. Zenoh fills its queue without
Python, so a drain takes everything that has reached the process, in order. A second,
ordinary subscription stamps each message's arrival the moment Python sees it (on its
own thread, as every subscriber's handler, and as a recorder stamps it). A drain gives
a message that stamp; one it takes before Python got round to stamping it (a busy
process) arrived at its send stamp moved onto this clock by the least lag stamped from
its sender (:class:`SenderClocks`), and never later than it was taken. So the taker's
own lateness never counts, and the times do not depend on when it takes."""

from __future__ import annotations

import threading
import time
from collections.abc import Callable
from typing import Any

import zenoh

from executive.bus.message import Message

POLL_CAPACITY = 4096  # messages a polled subscription holds until drained
SENDERS = 1024  # senders whose clock offset is kept (the oldest is forgotten first)
# a sender's least lag is the least of its messages of the last one or two such spans
# (ns): a sender's clock that steps back (a time service's correction) is believed again
# within two spans
SPAN = 30_000_000_000

Stamper = Callable[[Callable[[Message], None]], Any]  # subscribes a handler to the key


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
    """Each sender's clock seen from here: the least lag of its recent messages stamped
    on arrival (its clock's offset plus the transport's, as near as seen)."""

    def __init__(self) -> None:
        self._lags: dict[str, _Lag] = {}
        self._lock = threading.Lock()  # stamped on the subscriptions' threads

    def learn(self, sender: str, sent: int, arrived: int) -> None:
        """Take note of a message ``sent`` on its sender's clock that ``arrived`` (ns,
        this clock: when Python first saw it)."""
        lag = arrived - sent
        with self._lock:
            known = self._lags.get(sender)
            if known is None:
                if len(self._lags) >= SENDERS:
                    del self._lags[next(iter(self._lags))]
                self._lags[sender] = _Lag(lag, None, arrived)
            elif arrived - known.since >= SPAN:  # a new span
                recent = arrived - known.since < 2 * SPAN
                known.before = known.current if recent else None
                known.current, known.since = lag, arrived
            else:
                known.current = min(known.current, lag)

    def arrival(self, sender: str, sent: int, taken: int) -> int:
        """When a message ``sent`` on its sender's clock and ``taken`` now (ns) arrived,
        as near as known: its sent time on this clock, at most ``taken``."""
        with self._lock:
            known = self._lags.get(sender)
            least = None if known is None else known.least()
        return taken if least is None else min(taken, sent + least)


class Polled:
    """A subscription whose messages wait until taken (see the module documentation and
    :meth:`executive.bus.session.Bus.poll`)."""

    def __init__(
        self,
        queue: Any,
        message: Callable[[zenoh.Sample], Message | None],
        clocks: SenderClocks,
        stamper: Stamper,
        capacity: int = POLL_CAPACITY,
    ) -> None:
        self._queue = queue  # a zenoh subscriber with a ring channel
        self._message = message
        self._clocks = clocks  # shared by the session's polled keys
        self._capacity = capacity
        self._stamps: dict[tuple[str, int], int] = {}  # (sender, sent) -> arrived, until taken
        self._lock = threading.Lock()
        self._began = 0  # when the last drain began (ns)
        self._stamper = stamper(self._stamp)

    def drain(self) -> list[Message]:
        """Take every message that has arrived, oldest first."""
        began = time.time_ns()
        messages: list[Message] = []
        while (sample := self._queue.try_recv()) is not None:
            message = self._message(sample)
            if message is not None:
                messages.append(self._arrival(message))
        with self._lock:
            # a message stamped before the last drain was in the queue then: a stamp
            # still here is of one taken before it was stamped, or dropped
            for stale in [k for k, arrived in self._stamps.items() if arrived < self._began]:
                del self._stamps[stale]
            self._began = began
        return messages

    def _stamp(self, message: Message) -> None:
        """Note when a message arrived (on the stamping subscription's thread)."""
        sent = message.sent_ns
        if sent is None:
            return
        self._clocks.learn(message.caller_id, sent, message.received_ns)
        with self._lock:
            if len(self._stamps) >= self._capacity:  # nobody drains
                del self._stamps[next(iter(self._stamps))]
            self._stamps[message.caller_id, sent] = message.received_ns

    def _arrival(self, message: Message) -> Message:
        """The message with its ``received`` time when it arrived: its stamp, or for one
        not stamped yet its sent time on this clock, at most when it was taken."""
        sent = message.sent_ns
        if sent is None:
            return message
        with self._lock:
            arrived = self._stamps.pop((message.caller_id, sent), None)
        taken = message.received_ns
        if arrived is None:
            arrived = self._clocks.arrival(message.caller_id, sent, taken)
        return Message.at_ns(message.key, message.raw, message.caller_id, sent, min(arrived, taken))

    def undeclare(self) -> None:
        self._stamper.undeclare()
        self._queue.undeclare()
