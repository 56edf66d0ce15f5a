"""Change a parameter of a component through the executive."""

from __future__ import annotations

from typing import Any

from knowledge.yamlsource import Section, to_python
from monitoring.repair.action import Action, ActionContext, Firing
from monitoring.repair.actions.executive import ExecutiveAction


class ParameterAction(ExecutiveAction):
    """``executive/api/parameter/set`` with ``{component, key, value}``."""

    type = "parameter"
    verb = "parameter/set"

    def __init__(self, component: str, key: str, value: Any, timeout: float) -> None:
        super().__init__(timeout)
        self.component, self.key, self.value = component, key, value

    @classmethod
    def configure(cls, entry: Section, timeout: float) -> Action:
        component = cls._require(entry, "component")
        key = cls._require(entry, "key")
        node = entry.node("value")
        if node is None:
            entry.report.error(entry.line, f"{entry.what} has no 'value'")
        return cls(component, key, None if node is None else to_python(node), timeout)

    def _run(self, context: ActionContext, firing: Firing) -> None:
        payload = {"component": self.component, "key": self.key, "value": self.value}
        self.request(context, self.verb, payload)

    def describe(self) -> str:
        return f"set {self.component}.{self.key}"
