"""Restart a component through the task executor (counts as a fault of it)."""

from __future__ import annotations

from typing import ClassVar

from executive.bus.api import tasks as api
from executive.bus.verb import Verb
from knowledge.yamlsource import Section
from monitoring.repair.action import Action, ActionContext, Firing
from monitoring.repair.actions.executive import ExecutiveAction


class RestartAction(ExecutiveAction):
    """``component/restart`` of the task executor with ``{name, reason}``."""

    type = "restart"
    verb: ClassVar[Verb[api.ComponentFault, api.FaultReply]] = api.COMPONENT_RESTART

    def __init__(self, component: str, reason: str, timeout: float) -> None:
        super().__init__(timeout)
        self.component = component
        self.reason = reason

    @classmethod
    def configure(cls, entry: Section, timeout: float) -> Action:
        component = cls._require(entry, "component")
        return cls(component, entry.text("reason", "rule $rule fired") or "", timeout)

    def _run(self, context: ActionContext, firing: Firing) -> None:
        request = api.ComponentFault(firing.fill(self.component), firing.fill(self.reason))
        self.call(context, self.verb, request)

    def describe(self) -> str:
        return f"restart {self.component}"
