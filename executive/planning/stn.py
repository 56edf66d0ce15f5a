"""Turn a unified-planning plan into the partial order the plan executor runs.

A time-triggered plan becomes a simple temporal network with UP's own conversion
(``convert_to(PlanKind.STN_PLAN)``), whose constraints between the start points of
actions say how much later one action must start than another. Durations are only
estimates during execution, so each constraint becomes "start after the other step
has started" or, when it reaches past that step's duration, "after it has ended";
constraints that allow a step to start earlier than the other impose nothing. A
sequential plan (classical planners) is de-ordered with UP's partial-order conversion
and each step waits for the end of the steps before it.

Conditions and effects are grounded into :mod:`executive.planning.expression` trees. The
bookkeeping actions compiled for deadlines are left out, their orderings kept.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from fractions import Fraction
from typing import TYPE_CHECKING, Any

from unified_planning.model.timing import TimepointKind
from unified_planning.plans import PlanKind, SequentialPlan, TimeTriggeredPlan

from executive.planning.expression import Atom, Expression, Value, conjunction
from executive.planning.partial_order import (
    Effect,
    EffectKind,
    PartialOrderPlan,
    Precedence,
    Step,
    Timepoint,
)
from executive.planning.problem import BOOKKEEPING, bindings, from_fnode
from executive.planning.unavailable import is_availability
from knowledge.errors import DomainError

if TYPE_CHECKING:
    from unified_planning.model import Problem
    from unified_planning.plans import Plan

_TOLERANCE = Fraction(1, 10**6)


def partial_order(problem: Problem, plan: Plan) -> PartialOrderPlan:
    """The executable partial order of a sequential or time-triggered plan.

    Raises:
        DomainError: the plan has a kind or an expression dura cannot execute.
    """
    if isinstance(plan, TimeTriggeredPlan):
        return _from_timed(problem, plan)
    if isinstance(plan, SequentialPlan):
        return _from_sequential(problem, plan)
    raise DomainError(f"dura cannot execute a {type(plan).__name__}")


def _from_sequential(problem: Problem, plan: Any) -> PartialOrderPlan:
    instances = list(plan.actions)
    order = plan.convert_to(PlanKind.PARTIAL_ORDER_PLAN, problem)
    position = {id(ai): i for i, ai in enumerate(instances)}
    after: dict[int, set[Precedence]] = {i: set() for i in range(len(instances))}
    for ai, successors in order.get_adjacency_list.items():
        for succ in successors:
            after[position[id(succ)]].add(Precedence(position[id(ai)], Timepoint.END))
    timed = [(Fraction(i), ai, None) for i, ai in enumerate(instances)]
    return _steps(problem, timed, after)


def _from_timed(problem: Problem, plan: Any) -> PartialOrderPlan:
    timed = sorted(plan.timed_actions, key=lambda t: t[0])
    index = {id(ai): i for i, (_, ai, _) in enumerate(timed)}
    durations = [d for _, _, d in timed]
    stn = plan.convert_to(PlanKind.STN_PLAN, problem)
    # each step waits for (other step, timepoint); found from the STN's lower bounds
    waits: dict[int, set[Precedence]] = {i: set() for i in range(len(timed))}
    for source, edges in stn.get_constraints().items():
        if source.action_instance is None:
            continue  # the plan's global start and end
        a = index[id(source.action_instance)]
        for lower, _upper, target in edges:
            if target.action_instance is None or lower is None:
                continue
            b = index[id(target.action_instance)]
            if a == b:
                continue
            # start(b) >= start(a) + offset, whichever timepoints the edge joins
            offset = Fraction(lower)
            if source.kind == TimepointKind.END:
                offset += durations[a] or 0
            if target.kind == TimepointKind.END:
                offset -= durations[b] or 0
            if offset < -_TOLERANCE:
                continue
            ends = durations[a] is None or offset >= (durations[a] or 0) - _TOLERANCE
            waits[b].add(Precedence(a, Timepoint.END if ends else Timepoint.START))
    return _steps(problem, timed, waits)


def _steps(
    problem: Problem,
    timed: Sequence[tuple[Fraction, Any, Fraction | None]],
    waits: Mapping[int, set[Precedence]],
) -> PartialOrderPlan:
    """Ground the actions, drop bookkeeping ones (keeping their orderings), renumber."""
    keep = [i for i, (_, ai, _) in enumerate(timed) if not ai.action.name.startswith(BOOKKEEPING)]
    number = {old: new for new, old in enumerate(keep)}

    def resolved(i: int, seen: frozenset[int] = frozenset()) -> set[Precedence]:
        """What step i waits for, looking through the dropped steps it waits for."""
        out: set[Precedence] = set()
        for p in waits[i]:
            if p.step in number:
                out.add(Precedence(number[p.step], p.at))
            elif p.step not in seen:
                out |= resolved(p.step, seen | {i})
        return out

    steps: list[Step] = []
    for old in keep:
        start, ai, duration = timed[old]
        found = resolved(old)
        ended = {p.step for p in found if p.at is Timepoint.END}
        after = sorted(
            (p for p in found if p.at is Timepoint.END or p.step not in ended),
            key=lambda p: (p.step, p.at.value),
        )
        steps.append(
            _ground(problem, ai, number[old], float(start), _seconds(duration), after=tuple(after))
        )
    return PartialOrderPlan(tuple(steps))


def _seconds(duration: Fraction | None) -> float | None:
    return None if duration is None else float(duration)


def _ground(
    problem: Problem,
    ai: Any,
    index: int,
    start: float,
    duration: float | None,
    *,
    after: tuple[Precedence, ...],
) -> Step:
    """A step with the action's conditions and effects bound to its arguments."""
    action = ai.action
    names = tuple(p.name for p in action.parameters)
    args = tuple(str(a.object().name) for a in ai.actual_parameters)
    env = dict(zip(names, args, strict=True))
    at_start: list[Expression] = []
    over_all: list[Expression] = []
    at_end: list[Expression] = []
    start_effects: list[Effect] = []
    end_effects: list[Effect] = []
    if hasattr(action, "preconditions"):  # instantaneous or classical: effects at the end
        at_start = [
            from_fnode(c, problem, env) for c in action.preconditions if not is_availability(c)
        ]
        end_effects = [e for x in action.effects for e in _effects(x, problem, env)]
    else:
        for interval, conditions in action.conditions.items():
            ground = [from_fnode(c, problem, env) for c in conditions if not is_availability(c)]
            lower, upper = interval.lower, interval.upper
            if lower == upper:
                (at_start if lower.is_from_start() else at_end).extend(ground)
            else:
                over_all.extend(ground)
                if not interval.is_left_open():
                    at_start.extend(ground)
                if not interval.is_right_open():
                    at_end.extend(ground)
        for timing, effects in action.effects.items():
            bucket = start_effects if timing.is_from_start() else end_effects
            bucket.extend(e for x in effects for e in _effects(x, problem, env))
    return Step(
        index=index,
        action=action.name,
        args=args,
        parameters=names,
        start=start,
        duration=duration,
        after=after,
        at_start=conjunction(at_start),
        over_all=conjunction(over_all),
        at_end=conjunction(at_end),
        start_effects=tuple(start_effects),
        end_effects=tuple(end_effects),
    )


_KINDS = {
    "ASSIGN": EffectKind.ASSIGN,
    "INCREASE": EffectKind.INCREASE,
    "DECREASE": EffectKind.DECREASE,
}


def _effects(effect: Any, problem: Problem, env: Mapping[str, str]) -> list[Effect]:
    """A UP effect as ground effects (a ``forall`` effect expands over the objects)."""
    kind = _KINDS.get(effect.kind.name)
    if kind is None:
        raise DomainError(f"dura cannot apply the effect '{effect}'")
    out: list[Effect] = []
    for binding in bindings(effect.forall, problem) if effect.forall else [{}]:
        scope = {**env, **binding}
        target = from_fnode(effect.fluent, problem, scope)
        if not isinstance(target, (Atom, Value)):
            raise DomainError(f"dura cannot apply the effect '{effect}'")
        out.append(
            Effect(
                name=target.name,
                args=target.args,
                value=from_fnode(effect.value, problem, scope),
                kind=kind,
                condition=from_fnode(effect.condition, problem, scope),
            )
        )
    return out
