"""The lifecycles of goals, plans and tasks: their states and the changes allowed.

Apart from :mod:`knowledge.records` (which re-exports them) so that a caller that only
names a state, such as the planning API's goal query, does not build every record type.
"""

from __future__ import annotations

import enum
from collections.abc import Mapping


class GoalState(enum.Enum):
    """A goal's lifecycle: open (pending, planned, executing) until it ends.

    Unreachable is an end that the world may undo: the goal planner looks at such a
    goal again when the world changes. A maintenance goal (``keep``) that is achieved
    is watched, and pending again (re-posted) once it stops holding.
    """

    PENDING = "pending"
    PLANNED = "planned"
    EXECUTING = "executing"
    ACHIEVED = "achieved"
    FAILED = "failed"
    UNREACHABLE = "unreachable"
    CANCELLED = "cancelled"

    @property
    def is_open(self) -> bool:
        return self in (GoalState.PENDING, GoalState.PLANNED, GoalState.EXECUTING)

    @property
    def is_final(self) -> bool:
        """Whether nothing can change it any more (a maintenance goal's achieved is not)."""
        return not GOAL_TRANSITIONS[self]

    def can_become(self, state: GoalState, *, keep: bool = False) -> bool:
        """Whether a goal in this state may change to ``state`` (see GOAL_TRANSITIONS;
        a maintenance goal also KEEP_TRANSITIONS)."""
        return state in GOAL_TRANSITIONS[self] or (
            keep and state in KEEP_TRANSITIONS.get(self, frozenset())
        )


_GOAL_ENDS = frozenset(
    {GoalState.ACHIEVED, GoalState.FAILED, GoalState.UNREACHABLE, GoalState.CANCELLED}
)

GOAL_TRANSITIONS: Mapping[GoalState, frozenset[GoalState]] = {
    GoalState.PENDING: _GOAL_ENDS | {GoalState.PLANNED},
    # planned again: a new plan replaced the one it was planned in
    GoalState.PLANNED: _GOAL_ENDS | {GoalState.PLANNED, GoalState.EXECUTING},
    # planned again: replanning after a failed step, a new goal or a cancel
    GoalState.EXECUTING: _GOAL_ENDS | {GoalState.PLANNED},
    # the other ends are final: a cancelled goal is never planned again
    **{end: frozenset() for end in _GOAL_ENDS},
    # looked at again when the world changes: pending again once a plan reaches it,
    # unreachable for another reason; or cancelled by its user
    GoalState.UNREACHABLE: frozenset(
        {GoalState.PENDING, GoalState.UNREACHABLE, GoalState.CANCELLED}
    ),
}
"""The changes the knowledge base allows, from each goal state."""

KEEP_TRANSITIONS: Mapping[GoalState, frozenset[GoalState]] = {
    # re-posted once it stops holding; or no longer watched
    GoalState.ACHIEVED: frozenset({GoalState.PENDING, GoalState.CANCELLED}),
}
"""What a maintenance goal (``keep``) may do besides GOAL_TRANSITIONS."""


class PlanState(enum.Enum):
    """A plan's lifecycle: stored (pending), executing, and how it ended."""

    PENDING = "pending"
    EXECUTING = "executing"
    SUCCEEDED = "succeeded"
    FAILED = "failed"
    SUPERSEDED = "superseded"
    CANCELLED = "cancelled"  # ended because none of its goals was open any more

    def can_become(self, state: PlanState) -> bool:
        """Whether a plan in this state may change to ``state`` (see PLAN_TRANSITIONS)."""
        return state in PLAN_TRANSITIONS[self]


_PLAN_ENDS = frozenset(
    {PlanState.SUCCEEDED, PlanState.FAILED, PlanState.SUPERSEDED, PlanState.CANCELLED}
)

PLAN_TRANSITIONS: Mapping[PlanState, frozenset[PlanState]] = {
    PlanState.PENDING: _PLAN_ENDS - {PlanState.SUCCEEDED} | {PlanState.EXECUTING},
    PlanState.EXECUTING: _PLAN_ENDS,
    # a plan that ended stays as it ended (a superseded plan cannot fail afterwards)
    **{end: frozenset() for end in _PLAN_ENDS},
}
"""The changes the knowledge base allows, from each plan state."""


class TaskState(enum.Enum):
    PENDING = "pending"
    SCHEDULED = "scheduled"
    RUNNING = "running"
    PAUSED = "paused"
    SUCCEEDED = "succeeded"
    FAILED = "failed"
    CANCELLED = "cancelled"

    @property
    def is_final(self) -> bool:
        return self in (TaskState.SUCCEEDED, TaskState.FAILED, TaskState.CANCELLED)
