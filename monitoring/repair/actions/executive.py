"""What the actions that ask the executive have in common: one bus request."""

from __future__ import annotations

from typing import Any

from executive.bus.keys import api
from knowledge.errors import BusError
from monitoring.repair.action import Action, ActionContext


class ExecutiveAction(Action):
    """An action that is a request to ``executive/api/<verb>``."""

    verb: str

    def request(self, context: ActionContext, payload: dict[str, Any]) -> dict[str, Any]:
        """Send the request; an answer with ``ok: false`` is a failure naming its error."""
        reply = self._bus(context).request(api(self.verb), payload, timeout=self.timeout)
        if reply.get("ok") is False:
            raise BusError(f"{api(self.verb)}: {reply.get('error', 'refused')}")
        return reply

    def describe(self) -> str:
        return f"{self.type} via {api(self.verb)}"
