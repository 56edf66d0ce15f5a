"""Post a goal to the executive's goal planner."""

from __future__ import annotations

from knowledge.yamlsource import Section
from monitoring.repair.action import Action, ActionContext, Firing
from monitoring.repair.actions.executive import ExecutiveAction


class GoalAction(ExecutiveAction):
    """``executive/api/goal/add`` with ``{expression, priority, source: "rule"}``."""

    type = "goal"
    verb = "goal/add"

    def __init__(self, expression: str, priority: int, timeout: float) -> None:
        super().__init__(timeout)
        self.expression, self.priority = expression, priority

    @classmethod
    def configure(cls, entry: Section, timeout: float) -> Action:
        return cls(cls._require(entry, "expression"), entry.integer("goal_priority", 0), timeout)

    def _run(self, context: ActionContext, firing: Firing) -> None:
        self.request(
            context,
            {
                "expression": firing.fill(self.expression),
                "priority": self.priority,
                "source": "rule",
            },
        )

    def describe(self) -> str:
        return f"post goal {self.expression}"
