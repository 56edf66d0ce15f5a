"""A service's request on the bus, declared once: its key, request and reply types.

Every verb a service serves is a :class:`Verb` constant in one module of
:mod:`executive.bus.api`. The service serves it (:meth:`Verb.serve`) and every caller
(the CLI, the test harness, the dashboard, the rule engine, a component) calls it
(:meth:`Verb.call`) through that one declaration, so nobody types a key twice and a
request is checked in one place: a malformed one gets an error reply naming the key and
the reason, and the handler never sees it.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any, Generic, Protocol, Self, TypeVar

from executive.bus.schema import Payload
from executive.bus.session import Bus
from knowledge.errors import DuraError
from knowledge.record_class import record


class Codec(Protocol):
    """What a request or reply type offers (a :class:`Payload`, or a hand-written one)."""

    @classmethod
    def from_payload(cls, payload: dict[str, Any]) -> Self: ...

    def to_payload(self) -> dict[str, Any]: ...


Req = TypeVar("Req", bound=Codec)
Rep = TypeVar("Rep", bound=Codec)


@record
class Empty(Payload):
    """A request or reply without fields."""


@dataclass(frozen=True)
class Verb(Generic[Req, Rep]):
    """One request a service answers.

    Args:
        key: the key under ``dura/<robot>/``, e.g. ``executive/api/goal/add``.
        request, reply: their types.
        timeout: how long a caller waits by default, in seconds.
        threaded: answer each request on a thread of its own (handlers that wait for
            processes or other services must not hold Zenoh's callback thread).
        caller: a field of the request that names the caller: the verb is asked on
            ``<key>/<caller's name>`` (the bus session's), which access control checks,
            and the handler gets that name in the field, never what the caller wrote.
    """

    key: str
    request: type[Req]
    reply: type[Rep]
    timeout: float = 30.0
    threaded: bool = True
    caller: str = ""

    def serve(self, bus: Bus, handler: Callable[[Req], Rep]) -> Any:
        """Answer this verb on ``bus`` with ``handler``; returns the queryable."""
        key = self.key

        def answer(raw: dict[str, Any]) -> Mapping[str, Any]:
            try:
                request = self.request.from_payload(raw)
            except DuraError as e:
                raise DuraError(f"{key}: {e}") from e
            return handler(request).to_payload()

        return bus.serve(key, answer, threaded=self.threaded, caller=self.caller)

    def call(self, bus: Bus, request: Req | None = None, *, timeout: float | None = None) -> Rep:
        """Ask and wait for the reply.

        Raises:
            BusError: nobody answered in time, or the service refused (its reason).
            PayloadError: the reply does not fit the declared type.
        """
        payload = request.to_payload() if request is not None else {}
        wait = self.timeout if timeout is None else timeout
        reply = bus.request(self.key, payload, timeout=wait, as_caller=bool(self.caller))
        return self.reply.from_payload(reply)
