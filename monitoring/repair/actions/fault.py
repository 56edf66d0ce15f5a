"""Mark a component faulty through the task executor."""

from __future__ import annotations

from knowledge.yamlsource import Section
from monitoring.repair.action import Action, ActionContext, Firing
from monitoring.repair.actions.executive import ExecutiveAction


class FaultAction(ExecutiveAction):
    """``executive/api/component/fault`` with ``{name, reason}``."""

    type = "fault"
    verb = "component/fault"

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
        return f"mark {self.component} faulty"
