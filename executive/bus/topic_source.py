"""Topics whose messages do not travel on dura's bus, e.g. a robot's ROS 2 topics.

A :class:`TopicSource` serves some ``topic/<name>`` keys with :class:`Message` objects
that look like the bus's: the publisher's name as caller id, its send time, the
reception time, and a ``payload`` dict decoded only when someone reads it. The
composition root gives the sources to whoever subscribes to topics (the observer
manager), which asks them before the bus.
"""

from __future__ import annotations

from typing import Protocol

from executive.bus.session import Handler


class Subscription(Protocol):
    """What a subscription is to its owner: something to undeclare."""

    def undeclare(self) -> None:
        """Stop delivering messages (idempotent)."""


class TopicSource(Protocol):
    """Messages of some topic keys, delivered as the bus delivers its own."""

    def serves(self, key: str) -> bool:
        """Whether this source has the messages of a key (``topic/scan``)."""

    def subscribe(self, key: str, handler: Handler) -> Subscription:
        """Call ``handler`` with every message on a key it serves, from its own threads."""
