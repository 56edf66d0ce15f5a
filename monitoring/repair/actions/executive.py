"""What the actions that ask the executive have in common: one bus request."""

from __future__ import annotations

from typing import Any, TypeVar

from executive.bus.keys import api
from executive.bus.verb import Codec, Verb
from knowledge.errors import BusError
from monitoring.repair.action import Action, ActionContext

Req = TypeVar("Req", bound=Codec)
Rep = TypeVar("Rep", bound=Codec)


class ExecutiveAction(Action):
    """An action that is a request to the executive."""

    def call(self, context: ActionContext, verb: Verb[Req, Rep], request: Req) -> Rep:
        """Call a declared verb of the executive's API within the action's timeout."""
        return verb.call(self._bus(context), request, timeout=self.timeout)

    def request(self, context: ActionContext, verb: str, payload: dict[str, Any]) -> dict[str, Any]:
        """Send a request to ``executive/api/<verb>`` (a verb the rule names); an answer
        with ``ok: false`` is a failure naming its error."""
        reply = self._bus(context).request(api(verb), payload, timeout=self.timeout)
        if reply.get("ok") is False:
            raise BusError(f"{api(verb)}: {reply.get('error', 'refused')}")
        return reply
