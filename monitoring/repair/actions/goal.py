"""Post a goal to the executive's goal planner."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Annotated

from executive.bus.api import planning as api
from knowledge.conventions import Key, Required
from monitoring.repair.action import ActionContext, Firing
from monitoring.repair.actions.executive import ExecutiveAction


@dataclass(frozen=True, kw_only=True)
class GoalAction(ExecutiveAction):
    """``goal/add`` of the high level with ``{expression, priority, source: "rule"}``."""

    type = "goal"
    expression: Annotated[str, Required()] = ""
    priority: Annotated[int, Key("goal_priority")] = 0

    def _run(self, context: ActionContext, firing: Firing) -> None:
        request = api.GoalAdd(firing.fill(self.expression), self.priority, source="rule")
        self.call(context, api.GOAL_ADD, request)

    def describe(self) -> str:
        return f"post goal {self.expression}"
