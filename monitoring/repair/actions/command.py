"""Send a command (any verb) to the executive."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Annotated, Any

from knowledge.conventions import Check, Required
from monitoring.repair.action import ActionContext, Firing
from monitoring.repair.actions.executive import ExecutiveAction


@dataclass(frozen=True, kw_only=True)
class CommandAction(ExecutiveAction):
    """``executive/api/<verb>`` with ``payload`` (a mapping)."""

    type = "command"
    verb: Annotated[str, Required(), Check(lambda verb, place: verb.strip("/"))] = ""
    payload: dict[str, Any] = field(default_factory=dict)

    def describe(self) -> str:
        return f"command executive/api/{self.verb}"

    def _run(self, context: ActionContext, firing: Firing) -> None:
        payload = {k: firing.fill(v) if isinstance(v, str) else v for k, v in self.payload.items()}
        self.request(context, self.verb, payload)
