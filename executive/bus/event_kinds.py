"""The kinds of event dura writes to the knowledge base's event log.

Most kinds are names (``PLAN_START``, ``FAULT``); four families are composed from a
state: ``COMPONENT_<lifecycle>`` (the launcher), ``GOAL_<goal state>`` (the knowledge
base), ``GOAL_RESULT_<status>`` (a behavior's goal) and ``TASK_<end>`` (the task
executor). ``tests/executive/bus/test_event_kinds.py`` reads every ``log_event`` call of
dura and keeps this list true.
"""

from __future__ import annotations

from collections.abc import Mapping

from executive.bus.states import GoalStatus, Lifecycle
from knowledge.transitions import GoalState

NAMED = frozenset(
    {
        # the executive and the world
        "EXECUTIVE_STARTED", "EXECUTIVE_STOPPED", "WORLD_SEEDED", "STATE_SET",
        "STATE_UNSET", "STATE_TIMED", "OBJECT_ADDED", "OBJECT_REMOVED", "PARAMETER",
        # goals, plans and their steps
        "GOAL_ADDED", "PLANNING", "PLAN_STORED", "PLAN_START", "DISPATCH", "START", "END",
        "FAIL", "CANCEL", "ADOPT", "RECOVERED", "REPLAN", "INTEGRITY_GOAL",
        "INTEGRITY_REFUSED",
        # tasks, configurations, faults
        "TASK_REQUESTED", "TASK_SCHEDULED", "TASK_RECONFIGURED", "TASK_STARTED",
        "TASK_PAUSED", "TASK_RESUMED", "TASK_RESTARTED", "CONFIGURATION", "REPAIR", "FAULT",
        "PERMANENT_FAULT", "COMPONENT_RESET",
        # the computers of a robot (host agents)
        "HOST_JOINED", "HOST_LOST", "HOST_STOPPED",
        # the robots of a fleet (dura fleet run)
        "ROBOT_JOINED", "ROBOT_LOST",
        # monitoring
        "RULE_FIRED", "RULE_FAILED", "EXONERATION",
    }
)  # fmt: skip
"""The kinds logged under a name of their own."""

FAMILIES: Mapping[str, tuple[str, ...]] = {
    "COMPONENT_": tuple(s.name for s in Lifecycle),
    "GOAL_": tuple(s.name for s in GoalState),
    "GOAL_RESULT_": tuple(s.name for s in GoalStatus),
    # how a task ended: the final phases of executive.tasks.task.TaskPhase
    "TASK_": ("SUCCEEDED", "FAILED", "CANCELLED"),
}
"""The composed kinds: a prefix and the states that complete it."""

KINDS = NAMED | {prefix + state for prefix, states in FAMILIES.items() for state in states}
"""Every kind of event dura logs."""

WIDTH = max(len(k) for k in KINDS)
"""Characters of the longest kind: the width of a kind column."""


def known(kind: str) -> bool:
    """Whether dura logs events of this kind."""
    return kind in KINDS
