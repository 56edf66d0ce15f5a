"""Goals: PDDL goal expressions with a priority, an optional deadline and a source.

A goal is checked against the domain and the knowledge base's objects when it is
submitted: one that names an unknown predicate or object, or the wrong number or
types of arguments, is refused with the reason and nothing is stored. Goals live in
the knowledge base with their lifecycle (pending → planned → executing → achieved |
failed | unreachable | cancelled); the goal planner reads the open ones again each
time it plans, so a restarted executive continues them.
"""

from __future__ import annotations

import enum
import math
import time
from dataclasses import dataclass

from executive.bus.clock import Clock
from executive.planning.expression import Expression, Signature, parse
from knowledge.domain import DomainInfo
from knowledge.errors import DomainError
from knowledge.knowledge_base import KnowledgeBase
from knowledge.records import Goal

SOURCES = ("user", "integrity", "rule")


@dataclass(frozen=True)
class GoalSpec:
    """An open goal as the planner sees it; ``deadline`` is in seconds from now."""

    id: int
    expression: Expression
    priority: int = 0
    deadline: float | None = None


class RefusalCause(enum.Enum):
    """Why a stored goal cannot be planned for: the goal planner fails a goal whose
    deadline passed and finds the others unreachable."""

    DEADLINE_PASSED = "deadline_passed"
    INVALID = "invalid"  # no longer fits the domain and objects (an object was removed)


@dataclass(frozen=True)
class Refusal:
    """A stored goal the planner cannot use, why (typed), and the sentence for users."""

    cause: RefusalCause
    reason: str


def normalized(text: str) -> str:
    """A goal expression on one line, as it is stored and shown."""
    return " ".join(text.split())


def submit(
    kb: KnowledgeBase,
    domain: DomainInfo,
    text: str,
    *,
    priority: int = 0,
    deadline: float | None = None,
    source: str = "user",
    keep: bool = False,
) -> Goal:
    """Check a goal against the domain and the KB's objects, then store it as pending;
    ``keep``: a maintenance goal, re-posted whenever it stops holding.

    Raises:
        DomainError: the expression, deadline or source is invalid (nothing is stored).
    """
    text = normalized(text)
    if deadline is not None and (not math.isfinite(deadline) or deadline <= 0):
        raise DomainError(f"goal '{text}': the deadline must be a positive number of seconds")
    if source not in SOURCES:
        raise DomainError(f"goal '{text}': unknown source '{source}' (one of {', '.join(SOURCES)})")
    parse(text, Signature.of(domain, kb.objects()))
    return kb.add_goal(text, priority=priority, deadline=deadline, source=source, keep=keep)


def remaining(goal: Goal, now: float | None = None, clock: Clock | None = None) -> float | None:
    """Seconds of robot time left until a goal's deadline (negative once passed);
    ``None`` without one. ``now`` is wall-clock epoch seconds."""
    if goal.deadline is None:
        return None
    waited = (time.time() if now is None else now) - goal.created
    return goal.deadline - (clock or Clock()).robot(waited)


def specs(
    goals: list[Goal], signature: Signature, now: float | None = None, clock: Clock | None = None
) -> tuple[list[GoalSpec], dict[int, Refusal]]:
    """Read stored goals for planning: the usable ones, and the refusal of each other one.

    A goal is unusable when it no longer fits the domain and objects (an object was
    removed) or its deadline has passed.
    """
    now = time.time() if now is None else now
    usable: list[GoalSpec] = []
    refused: dict[int, Refusal] = {}
    for goal in goals:
        try:
            expression = parse(goal.expression, signature)
        except DomainError as e:
            refused[goal.id] = Refusal(RefusalCause.INVALID, str(e))
            continue
        left = remaining(goal, now, clock)
        if left is not None and left <= 0:
            refused[goal.id] = Refusal(
                RefusalCause.DEADLINE_PASSED, f"its deadline of {goal.deadline:g} s passed"
            )
            continue
        usable.append(GoalSpec(goal.id, expression, goal.priority, left))
    return usable, refused
