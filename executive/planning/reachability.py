"""Relaxed reachability: what no sequence of actions can ever make true from a state.

The delete relaxation: start from the true atoms, apply every ground action whose
conditions can hold, add its positive effects and never take an atom away, until
nothing new is added. Negative conditions and numeric comparisons are taken to hold
(optimistically), so the analysis over-approximates what a planner can reach: an atom
it does not reach can never become true, an action it never applies can never be
applied, and a goal atom it does not reach is a reason a goal is unreachable that a
user can act on (``dura state set``, a new object, a repaired component). It says
nothing about goals it does reach.

Durative actions: an at-start condition must hold before the action; over-all and
at-end conditions may also hold through the action's own at-start effects.

Used by the planner's worker to say what an unreachable goal is missing, and by ``dura
domain check`` for actions that can never be applied from a problem's initial state.
"""

from __future__ import annotations

import itertools
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from executive.planning.expression import (
    And,
    Atom,
    Compare,
    Const,
    Expression,
    Not,
    Or,
    conjunction,
)
from executive.planning.problem import BOOKKEEPING, bindings, from_fnode
from knowledge.errors import DomainError

if TYPE_CHECKING:
    from unified_planning.model import Problem

Key = tuple[str, tuple[str, ...]]
GROUND_LIMIT = 20_000  # ground actions beyond which the analysis is not attempted
SHOWN = 2  # achievers named per missing atom


@dataclass(frozen=True)
class GroundAction:
    """A ground action, reduced to what the relaxation needs."""

    name: str
    args: tuple[str, ...]
    before: Expression  # holds before any of its effects (at start, preconditions)
    during: Expression  # over all and at end: its own at-start effects may help
    start_adds: frozenset[Key]
    adds: frozenset[Key]  # every atom it may make true (at start and at end)

    @property
    def label(self) -> str:
        return f"{self.name}({', '.join(self.args)})"


@dataclass(frozen=True)
class Reachability:
    """The atoms the relaxation reaches and the actions it applies (by index)."""

    actions: tuple[GroundAction, ...]
    reached: frozenset[Key]
    applied: frozenset[int]

    def holds(self, expression: Expression) -> bool:
        """Tell whether a condition may ever hold (optimistic for negations and numbers)."""
        return possible(expression, self.reached)

    def missing(self, goal: Expression) -> list[Expression]:
        """Return the parts of a goal that can never hold: atoms no action makes true, or a
        disjunction none of whose parts can."""
        parts = goal.args if isinstance(goal, And) else (goal,)
        return [p for p in parts if not possible(p, self.reached)]

    def never_applied(self) -> list[GroundAction]:
        """Return the ground actions the relaxation never applied."""
        return [a for i, a in enumerate(self.actions) if i not in self.applied]

    def explain(self, atom: Expression) -> str:
        """Say why an atom can never hold: ``(picture_taken dock) cannot become true:
        take_picture(dock) needs (photographable dock)``."""
        if not isinstance(atom, Atom):
            return f"{atom} cannot become true"
        key = (atom.name, atom.args)
        achievers = [a for a in self.actions if key in a.adds]
        if not achievers:
            return f"{atom} cannot become true: no action makes it true"
        reasons = []
        for action in achievers[:SHOWN]:
            lacking = _lacking(action.before, self.reached) or _lacking(
                action.during, self.reached | action.start_adds
            )
            needs = " and ".join(str(x) for x in lacking[:SHOWN]) or "its conditions"
            reasons.append(f"{action.label} needs {needs}")
        more = f" (and {len(achievers) - SHOWN} more)" if len(achievers) > SHOWN else ""
        return f"{atom} cannot become true: " + "; ".join(reasons) + more


def possible(expression: Expression, reached: frozenset[Key] | set[Key]) -> bool:
    """Tell whether a condition may hold once the atoms in ``reached`` are true."""
    e = expression
    if isinstance(e, Const):
        return bool(e.value)
    if isinstance(e, Atom):
        return (e.name, e.args) in reached
    if isinstance(e, And):
        return all(possible(a, reached) for a in e.args)
    if isinstance(e, Or):
        return any(possible(a, reached) for a in e.args)
    if isinstance(e, (Not, Compare)):
        return True  # deletes and numbers are relaxed away
    raise TypeError(f"{e} is a number, not a condition")


def _lacking(expression: Expression, reached: frozenset[Key] | set[Key]) -> list[Expression]:
    """Return the atoms (or disjunctions) of a condition that keep it from holding."""
    parts = expression.args if isinstance(expression, And) else (expression,)
    return [p for p in parts if not possible(p, reached)]


def closure(actions: Sequence[GroundAction], facts: Iterable[Key]) -> Reachability:
    """Apply the relaxed actions from the true atoms until nothing new is reached."""
    reached = set(facts)
    applied: set[int] = set()
    changed = True
    while changed:
        changed = False
        for i, action in enumerate(actions):
            if i in applied or not possible(action.before, reached):
                continue
            if not possible(action.during, reached | action.start_adds):
                continue
            applied.add(i)
            if not action.adds <= reached:
                reached |= action.adds
                changed = True
    return Reachability(tuple(actions), frozenset(reached), frozenset(applied))


# --- grounding a unified-planning problem ----------------------------------------------


def ground(problem: Problem, limit: int = GROUND_LIMIT) -> list[GroundAction] | None:
    """Ground every action of a problem (dura's bookkeeping actions included); ``None``
    when there would be more than ``limit``."""
    choices = []
    total = 0
    for action in problem.actions:
        domains = [[o.name for o in problem.objects(p.type)] for p in action.parameters]
        count = 1
        for d in domains:
            count *= len(d)
        total += count
        if total > limit:
            return None
        choices.append((action, domains))
    out: list[GroundAction] = []
    for action, domains in choices:
        names = [p.name for p in action.parameters]
        for args in itertools.product(*domains):
            try:
                out.append(_ground(problem, action, dict(zip(names, args, strict=True))))
            except DomainError:
                continue  # something dura cannot evaluate: leave the action out
    return out


def _ground(problem: Problem, action: Any, env: dict[str, str]) -> GroundAction:
    before: list[Expression] = []
    during: list[Expression] = []
    start_adds: set[Key] = set()
    adds: set[Key] = set()
    if hasattr(action, "preconditions"):
        before = [from_fnode(c, problem, env) for c in action.preconditions]
        adds = _adds(action.effects, problem, env)
    else:
        for interval, conditions in action.conditions.items():
            ground = [from_fnode(c, problem, env) for c in conditions]
            at_start = interval.lower == interval.upper and interval.lower.is_from_start()
            (before if at_start else during).extend(ground)
        for timing, effects in action.effects.items():
            found = _adds(effects, problem, env)
            adds |= found
            if timing.is_from_start():
                start_adds |= found
    args = tuple(env.values())
    return GroundAction(
        action.name, args, conjunction(before), conjunction(during),
        frozenset(start_adds), frozenset(adds),
    )  # fmt: skip


def _adds(effects: Iterable[Any], problem: Problem, env: Mapping[str, str]) -> set[Key]:
    """Return the atoms effects may make true (conditions of conditional effects ignored)."""
    out: set[Key] = set()
    for effect in effects:
        for binding in bindings(effect.forall, problem) if effect.forall else [{}]:
            scope = {**env, **binding}
            target = from_fnode(effect.fluent, problem, scope)
            if isinstance(target, Atom):
                value = from_fnode(effect.value, problem, scope)
                if value != Const(False):
                    out.add((target.name, target.args))
    return out


def problem_facts(problem: Problem) -> set[Key]:
    """Return the atoms true in a problem's initial state (explicit and default values)."""
    out: set[Key] = set()
    for fluent_exp, value in problem.initial_values.items():
        if value.is_bool_constant() and value.bool_constant_value():
            args = tuple(str(a.object().name) for a in fluent_exp.args)
            out.add((fluent_exp.fluent().name, args))
    return out


def missing_atoms(problem: Problem, goals: Sequence[Expression]) -> tuple[str, ...]:
    """Say why goals of a problem can never hold from its initial state, one line per goal
    part that no relaxed plan reaches (empty: the relaxation reaches every goal, or the
    problem is too large to ground)."""
    actions = ground(problem)
    if actions is None:
        return ()
    reach = closure(actions, problem_facts(problem))
    out: list[str] = []
    for goal in goals:
        for part in reach.missing(goal):
            line = reach.explain(part)
            if line not in out and BOOKKEEPING not in line:
                out.append(line)
    return tuple(out)
