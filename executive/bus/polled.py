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


class Polled:
    """A subscription whose messages wait until taken (see
    :meth:`executive.bus.session.Bus.poll`)."""

    def __init__(
        self,
        subscriber: Any,
        message: Callable[[zenoh.Sample], Message | None],
        offsets: dict[str, int],
    ) -> None:
        self._subscriber = subscriber
        self._message = message
        self._offsets = offsets  # sender -> least (taken - sent) so far (ns), on any key

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
        sender's clock onto this one."""
        sent, taken = message.sent_ns, message.received_ns
        if sent is None:
            return message
        known = self._offsets.get(message.caller_id)
        if known is None and len(self._offsets) >= SENDERS:
            del self._offsets[next(iter(self._offsets))]
        offset = taken - sent if known is None else min(known, taken - sent)
        self._offsets[message.caller_id] = offset
        return Message.at_ns(
            message.key, message.raw, message.caller_id, sent, min(taken, sent + offset)
        )

    def undeclare(self) -> None:
        self._subscriber.undeclare()
