"""Restart a component through the task executor (counts as a fault of it)."""

from __future__ import annotations

from knowledge.yamlsource import Section
from monitoring.repair.action import Action, ActionContext, Firing
from monitoring.repair.actions.executive import ExecutiveAction


class RestartAction(ExecutiveAction):
    """``executive/api/component/restart`` with ``{name, reason}``."""

    type = "restart"
    verb = "component/restart"

    def __init__(self, component: str, reason: str, timeout: float) -> None:
        super().__init__(timeout)
        self.component = component
        self.reason = reason

    @classmethod
    def configure(cls, entry: Section, timeout: float) -> Action:
        component = cls._require(entry, "component")
        return cls(component, entry.text("reason", "rule $rule fired") or "", timeout)

    def _run(self, context: ActionContext, firing: Firing) -> None:
        self.request(
            context, {"name": firing.fill(self.component), "reason": firing.fill(self.reason)}
        )

    def describe(self) -> str:
        return f"restart {self.component}"
