"""A plan as the plan executor runs it: steps in a partial order, with ground conditions
and effects (thesis 5.1.2, "the plan executor turns the plan into a partial order").

Pure data: :mod:`executive.planning.stn` builds it from a unified-planning plan. A step may start
when every step it comes after has reached the named timepoint (started or ended) and
its at-start condition holds in the knowledge base's facts.
"""

from __future__ import annotations

import enum
from collections.abc import Iterable
from dataclasses import dataclass

from executive.planning.expression import TRUE, Const, Expression, Value, WorldState
from knowledge.records import Fact, PlanStep


class Timepoint(enum.Enum):
    START = "start"
    END = "end"


class EffectKind(enum.Enum):
    ASSIGN = "assign"
    INCREASE = "increase"
    DECREASE = "decrease"


@dataclass(frozen=True)
class Effect:
    """A ground effect: ``(robot_at lab)`` becomes true, ``(battery r)`` decreases by 5.

    ``value`` is ``Const(True/False)`` for a predicate and a numeric expression for a
    function, evaluated in the state before the timepoint's effects (PDDL semantics).
    """

    name: str
    args: tuple[str, ...]
    value: Expression
    kind: EffectKind = EffectKind.ASSIGN
    condition: Expression = TRUE

    def fact(self, state: WorldState) -> Fact | None:
        """The fact this effect sets in a state; ``None`` if its condition is false or
        its value is unknown."""
        if not state.holds(self.condition):
            return None
        if isinstance(self.value, Const) and isinstance(self.value.value, bool):
            return Fact(self.name, self.args, self.value.value)
        value = state.number(self.value)
        if value is None:
            return None
        if self.kind is not EffectKind.ASSIGN:
            current = state.number(Value(self.name, self.args))
            if current is None:
                return None
            value = current + value if self.kind is EffectKind.INCREASE else current - value
        return Fact(self.name, self.args, value)

    def __str__(self) -> str:
        atom = "(" + " ".join((self.name, *self.args)) + ")"
        if isinstance(self.value, Const) and isinstance(self.value.value, bool):
            text = atom if self.value.value else f"(not {atom})"
        else:
            text = f"({self.kind.value if self.kind is not EffectKind.ASSIGN else 'assign'} {atom} {self.value})"
        return text if self.condition == TRUE else f"(when {self.condition} {text})"


def apply(effects: Iterable[Effect], state: WorldState) -> tuple[list[Fact], list[Fact]]:
    """The facts to add and to remove for effects happening together in a state."""
    add: list[Fact] = []
    remove: list[Fact] = []
    for effect in effects:
        fact = effect.fact(state)
        if fact is None:
            continue
        (remove if fact.value is False else add).append(fact)
    return add, remove


@dataclass(frozen=True)
class Precedence:
    """A step waits until step ``step`` has reached ``at`` (started or ended)."""

    step: int
    at: Timepoint


@dataclass(frozen=True)
class Step:
    """One ground action of a plan and what the executor checks and applies for it.

    ``start`` and ``duration`` are the planner's estimates (seconds from the plan's
    start); ``duration`` is ``None`` for an instantaneous or classical action, whose
    effects are applied when its task ends.
    """

    index: int
    action: str
    args: tuple[str, ...]
    parameters: tuple[str, ...]
    start: float
    duration: float | None = None
    after: tuple[Precedence, ...] = ()
    at_start: Expression = TRUE
    over_all: Expression = TRUE
    at_end: Expression = TRUE
    start_effects: tuple[Effect, ...] = ()
    end_effects: tuple[Effect, ...] = ()

    @property
    def bindings(self) -> dict[str, str]:
        """Parameter name (without ``?``) → object, for a task's behavior goal."""
        return dict(zip(self.parameters, self.args, strict=True))

    @property
    def label(self) -> str:
        return f"{self.action}({', '.join(self.args)})"


@dataclass(frozen=True)
class PartialOrderPlan:
    """The steps of a plan, indexed 0..n-1 in order of their planned start."""

    steps: tuple[Step, ...] = ()

    @property
    def makespan(self) -> float:
        return max((s.start + (s.duration or 0.0) for s in self.steps), default=0.0)

    def records(self) -> tuple[PlanStep, ...]:
        """The steps as the knowledge base stores them."""
        return tuple(PlanStep(s.index, s.action, s.args, s.start, s.duration) for s in self.steps)

    def roots(self) -> list[Step]:
        """The steps that come after no other step."""
        return [s for s in self.steps if not s.after]
