"""What the knowledge base stores, as typed frozen records (thesis tables 5.1-5.3)."""

from __future__ import annotations

import dataclasses
import enum
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any


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

    def can_become(self, state: PlanState) -> bool:
        """Whether a plan in this state may change to ``state`` (see PLAN_TRANSITIONS)."""
        return state in PLAN_TRANSITIONS[self]


PLAN_TRANSITIONS: Mapping[PlanState, frozenset[PlanState]] = {
    PlanState.PENDING: frozenset({PlanState.EXECUTING, PlanState.FAILED, PlanState.SUPERSEDED}),
    PlanState.EXECUTING: frozenset({PlanState.SUCCEEDED, PlanState.FAILED, PlanState.SUPERSEDED}),
    # a plan that ended stays as it ended (a superseded plan cannot fail afterwards)
    PlanState.SUCCEEDED: frozenset(),
    PlanState.FAILED: frozenset(),
    PlanState.SUPERSEDED: frozenset(),
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


@dataclass(frozen=True)
class Goal:
    """A PDDL goal expression to achieve, with its lifecycle."""

    id: int
    expression: str
    state: GoalState
    priority: int = 0
    deadline: float | None = None
    source: str = "user"
    reason: str = ""
    created: float = 0.0
    updated: float = 0.0
    keep: bool = False  # a maintenance goal: re-posted whenever it stops holding


@dataclass(frozen=True)
class PlanStep:
    """One action of a plan: what, with which objects, when and for how long."""

    index: int
    action: str
    args: tuple[str, ...]
    start: float
    duration: float | None = None


@dataclass(frozen=True)
class Plan:
    id: int
    state: PlanState
    steps: tuple[PlanStep, ...]
    engine: str = ""
    goal_ids: tuple[int, ...] = ()
    reason: str = ""
    created: float = 0.0
    updated: float = 0.0


@dataclass(frozen=True)
class Task:
    """A request to run a behavior for a PDDL action (or for a user)."""

    id: int
    action: str
    behavior: str
    args: Mapping[str, Any]
    state: TaskState
    plan_id: int | None = None
    step: int | None = None
    result: Any = None
    reason: str = ""
    created: float = 0.0
    updated: float = 0.0


@dataclass(frozen=True)
class Fact:
    """A ground PDDL atom and its value: True for a predicate, a number for a function."""

    name: str
    args: tuple[str, ...] = ()
    value: bool | float = True

    def __str__(self) -> str:
        atom = "(" + " ".join((self.name, *self.args)) + ")"
        if isinstance(self.value, bool):
            return atom if self.value else f"(not {atom})"
        return f"(= {atom} {self.value:g})"


@dataclass(frozen=True)
class ComponentRecord:
    """What the robot remembers about a component across restarts."""

    name: str
    rating: float
    fault_count: int = 0
    permanent_fault: bool = False
    reason: str = ""
    updated: float = 0.0


@dataclass(frozen=True)
class Event:
    """One entry of the append-only execution trace."""

    id: int
    stamp: float
    kind: str
    subject: str = ""
    data: Mapping[str, Any] = field(default_factory=dict)


def to_plain(record: object) -> Any:
    """A record (or a structure of records) as JSON-ready data; enums by value."""
    if dataclasses.is_dataclass(record) and not isinstance(record, type):
        return {f.name: to_plain(getattr(record, f.name)) for f in dataclasses.fields(record)}
    if isinstance(record, enum.Enum):
        return record.value
    if isinstance(record, (list, tuple)):
        return [to_plain(x) for x in record]
    if isinstance(record, Mapping):
        return {str(k): to_plain(v) for k, v in record.items()}
    return record
