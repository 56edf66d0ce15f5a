"""What the knowledge base stores, as typed frozen records (thesis tables 5.1-5.3)."""

from __future__ import annotations

import dataclasses
import enum
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

from knowledge.transitions import (
    GOAL_TRANSITIONS,
    KEEP_TRANSITIONS,
    PLAN_TRANSITIONS,
    GoalState,
    PlanState,
    TaskState,
)

__all__ = [  # the states live in knowledge.transitions; records names them too
    "GOAL_TRANSITIONS",
    "KEEP_TRANSITIONS",
    "PLAN_TRANSITIONS",
    "STEP_STATES",
    "ComponentRecord",
    "Event",
    "Fact",
    "Goal",
    "GoalState",
    "Plan",
    "PlanState",
    "PlanStep",
    "Task",
    "TaskState",
    "to_plain",
]


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


STEP_STATES = ("pending", "dispatched", "running", "ended", "failed", "cancelled", "adopted")
"""What happened to a stored plan step: not run (yet), asked of the task executor,
running, and how it ended; ``adopted``: the next plan continues it (as its own step)."""


@dataclass(frozen=True)
class PlanStep:
    """One action of a plan: what, with which objects, when and for how long, and what
    happened to it (one of :data:`STEP_STATES`)."""

    index: int
    action: str
    args: tuple[str, ...]
    start: float
    duration: float | None = None
    state: str = "pending"


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
