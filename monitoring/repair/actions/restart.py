"""Restart a component through the task executor (counts as a fault of it)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Annotated, ClassVar

from executive.bus.api import tasks as api
from executive.bus.verb import Verb
from knowledge.conventions import Required
from monitoring.repair.action import ActionContext, Firing
from monitoring.repair.actions.executive import ExecutiveAction


@dataclass(frozen=True, kw_only=True)
class RestartAction(ExecutiveAction):
    """``component/restart`` of the task executor with ``{name, reason}``."""

    type = "restart"
    verb: ClassVar[Verb[api.ComponentFault, api.FaultReply]] = api.COMPONENT_RESTART
    component: Annotated[str, Required()] = ""
    reason: str = "rule $rule fired"

    def _run(self, context: ActionContext, firing: Firing) -> None:
        request = api.ComponentFault(firing.fill(self.component), firing.fill(self.reason))
        self.call(context, self.verb, request)

    def describe(self) -> str:
        return f"restart {self.component}"
