"""Post a goal to the executive's goal planner."""

from __future__ import annotations

from executive.bus.api import planning as api
from knowledge.yamlsource import Section
from monitoring.repair.action import Action, ActionContext, Firing
from monitoring.repair.actions.executive import ExecutiveAction


class GoalAction(ExecutiveAction):
    """``goal/add`` of the high level with ``{expression, priority, source: "rule"}``."""

    type = "goal"

    def __init__(self, expression: str, priority: int, timeout: float) -> None:
        super().__init__(timeout)
        self.expression, self.priority = expression, priority

    @classmethod
    def configure(cls, entry: Section, timeout: float) -> Action:
        return cls(cls._require(entry, "expression"), entry.integer("goal_priority", 0), timeout)

    def _run(self, context: ActionContext, firing: Firing) -> None:
        request = api.GoalAdd(firing.fill(self.expression), self.priority, source="rule")
        self.call(context, api.GOAL_ADD, request)

    def describe(self) -> str:
        return f"post goal {self.expression}"
