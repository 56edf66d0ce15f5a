"""What the knowledge base stores, as typed frozen records (thesis tables 5.1-5.3).

A record is a frozen dataclass declared with :func:`~knowledge.record_class.record`:
compared, hashed and shown by its fields as ``@dataclass(frozen=True)`` makes one, but
made at a fraction of the cost (a quick command such as ``dura status`` reads them).
"""

from __future__ import annotations

import dataclasses
import enum
import warnings
from collections.abc import Mapping
from dataclasses import field
from typing import Any, TypeVar

from knowledge.record_class import record
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
    "KeyAccess",
    "Plan",
    "PlanState",
    "PlanStep",
    "Task",
    "TaskState",
    "record",
    "to_plain",
]

T = TypeVar("T")


class KeyAccess:
    """``record["key"]`` and ``record.get("key")``, as the dicts that the test harness
    returned before records are read: deprecated (a DeprecationWarning names the
    attribute to use); the value is the field as JSON data, as the dict held it."""

    def __getitem__(self, key: str) -> Any:
        if key not in _names(self):
            raise KeyError(key)
        return self._deprecated(key, f"[{key!r}]")

    def get(self, key: str, default: Any = None) -> Any:
        if key not in _names(self):
            return default
        return self._deprecated(key, f".get({key!r})")

    def _deprecated(self, key: str, spelled: str) -> Any:
        warnings.warn(
            f"{type(self).__name__}{spelled} is deprecated: use .{key}",
            DeprecationWarning,
            stacklevel=3,
        )
        return to_plain(getattr(self, key))


def _names(record: object) -> set[str]:
    return {f.name for f in dataclasses.fields(record)}  # type: ignore[arg-type]


@record
class Goal(KeyAccess):
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


@record
class PlanStep:
    """One action of a plan: what, with which objects, when and for how long, and what
    happened to it (one of :data:`STEP_STATES`)."""

    index: int
    action: str
    args: tuple[str, ...]
    start: float
    duration: float | None = None
    state: str = "pending"


@record
class Plan:
    """A plan the goal planner stored: its steps, the engine that found it, the goals it
    is for, and its lifecycle."""

    id: int
    state: PlanState
    steps: tuple[PlanStep, ...]
    engine: str = ""
    goal_ids: tuple[int, ...] = ()
    reason: str = ""
    created: float = 0.0
    updated: float = 0.0


@record
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


@record
class Fact:
    """A ground PDDL atom and its value: True for a predicate, a number for a function;
    ``text`` is the fact as PDDL, ``(robot_at lab)``, ``(= (battery) 80)``."""

    name: str
    args: tuple[str, ...] = ()
    value: bool | float = True
    text: str = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        atom = "(" + " ".join((self.name, *self.args)) + ")"
        if isinstance(self.value, bool):
            text = atom if self.value else f"(not {atom})"
        else:
            text = f"(= {atom} {self.value:g})"
        object.__setattr__(self, "text", text)

    def __str__(self) -> str:
        return self.text


@record
class TimedFact:
    """A fact that takes effect at a time (wall clock, seconds since the epoch): "the
    door opens at 14:00". Until then the planner plans with it as a timed initial
    literal; at ``at`` it becomes a fact of the world."""

    fact: Fact
    at: float

    def __str__(self) -> str:
        return f"{self.fact} at {self.at:.3f}"


@record
class ComponentRecord:
    """What the robot remembers about a component across restarts."""

    name: str
    rating: float
    fault_count: int = 0
    permanent_fault: bool = False
    reason: str = ""
    updated: float = 0.0


@record
class Event(KeyAccess):
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
