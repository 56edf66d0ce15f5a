"""Change a parameter of a component through the executive."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Annotated, Any, ClassVar

from knowledge.conventions import Required
from monitoring.repair.action import ActionContext, Firing
from monitoring.repair.actions.executive import ExecutiveAction


@dataclass(frozen=True, kw_only=True)
class ParameterAction(ExecutiveAction):
    """``executive/api/parameter/set`` with ``{component, key, value}``."""

    type = "parameter"
    verb: ClassVar[str] = "parameter/set"
    component: Annotated[str, Required()] = ""
    key: Annotated[str, Required()] = ""
    value: Annotated[Any, Required()] = None

    def _run(self, context: ActionContext, firing: Firing) -> None:
        payload = {"component": self.component, "key": self.key, "value": self.value}
        self.request(context, self.verb, payload)

    def describe(self) -> str:
        return f"set {self.component}.{self.key}"
