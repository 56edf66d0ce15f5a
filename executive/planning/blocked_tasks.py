"""The tasks that cannot run with the permanently faulty components, and when that
changes (a fault that blocks a task, a reset that frees it): then the plan changes."""

from __future__ import annotations

from knowledge.availability import blocked_tasks
from knowledge.description import RobotDescription
from knowledge.knowledge_base import KnowledgeBase


def blocked_now(kb: KnowledgeBase, robot: RobotDescription) -> dict[str, str]:
    """The tasks that cannot run with the permanently faulty components, and why."""
    faulty = [c.name for c in kb.components() if c.permanent_fault]
    return blocked_tasks(robot, faulty)


class BlockedTasks:
    """Tells when the blocked tasks changed since it last looked (first: when built)."""

    def __init__(self, kb: KnowledgeBase, robot: RobotDescription) -> None:
        self.kb = kb
        self.robot = robot
        self._last = blocked_now(kb, robot)

    def now(self) -> dict[str, str]:
        """The tasks blocked now, and why."""
        return blocked_now(self.kb, self.robot)

    def change(self) -> str | None:
        """Why to replan, if a task can no longer run or can run again; else None."""
        blocked = self.now()
        if blocked.keys() == self._last.keys():
            return None
        lost = sorted(blocked.keys() - self._last.keys())
        back = sorted(self._last.keys() - blocked.keys())
        self._last = blocked
        if lost:
            return f"{', '.join(lost)} can no longer run ({blocked[lost[0]]})"
        return f"{', '.join(back)} can run again"
