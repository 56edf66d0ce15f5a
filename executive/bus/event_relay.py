"""The relay of events between processes: every process of a robot runs one.

Every event this process logs in the knowledge base goes out on the bus key ``events``
(for ``dura events --follow``, the dashboard, the recorder, and the high level of
another process); the events other processes publish there (a task executor or repair
rules that run apart) come in. Both reach the followers (the high level's), as
``(kind, subject)``: the events of another process are in the knowledge base already.
"""

from __future__ import annotations

import contextlib
import logging
from collections.abc import Callable
from typing import Any

from executive.bus.keys import EVENTS
from executive.bus.message import Message
from executive.bus.service import Context, Service
from knowledge.records import Event, to_plain

log = logging.getLogger("dura.events")

Follower = Callable[[str, str], None]
"""Told of each event, of this process or another, as (kind, subject)."""


class EventRelay(Service):
    """Publishes this process's events and hands every process's events to followers.

    It relays from :meth:`configure` on (first in every process: the events of the other
    services' configuration go out too) until :meth:`shutdown`.
    """

    name = "event-relay"

    def __init__(self, context: Context) -> None:
        super().__init__(context)
        self._followers: list[Follower] = []
        self._listening = False  # the knowledge base's listener is in (it stays)
        self._relaying = False
        self._subscription: Any = None

    def follow(self, follower: Follower) -> None:
        """Hand every event to ``follower`` from now on (add followers before
        :meth:`configure`: only then are other processes' events heard)."""
        self._followers.append(follower)

    def on_configure(self) -> None:
        if not self._listening:
            self.context.kb.add_listener(self._logged)
            self._listening = True
        self._relaying = True
        if self._followers:
            self._subscription = self.context.bus.subscribe(EVENTS, self._heard)

    def on_shutdown(self) -> None:
        self._relaying = False
        if self._subscription is not None:
            with contextlib.suppress(Exception):  # already closed with the bus
                self._subscription.undeclare()
            self._subscription = None

    def _logged(self, event: Event) -> None:
        """An event this process logged: on the bus for all, then to the followers."""
        if not self._relaying:
            return
        self.context.bus.publish(EVENTS, to_plain(event))
        self._tell(event.kind, event.subject)

    def _heard(self, message: Message) -> None:
        """An event another process logged (its own are followed as they are logged)."""
        if message.caller_id == self.context.bus.name or not self._relaying:
            return
        payload = message.payload
        if not isinstance(payload, dict) or not isinstance(payload.get("kind"), str):
            log.warning("ignored a malformed event from %s", message.caller_id or "?")
            return
        self._tell(payload["kind"], str(payload.get("subject", "")))

    def _tell(self, kind: str, subject: str) -> None:
        for follower in self._followers:
            follower(kind, subject)
