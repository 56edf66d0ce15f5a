"""Plan for as many open goals as possible, by priority (oversubscription).

First all goals are planned together. If no plan reaches them all, goals are taken in
order of priority (higher first, older first among equals) and each is kept only if a
plan reaches it together with the goals kept before it. The kept set is then the best
by priority: no goal is given up for any number of goals of lower priority. Every goal
given up gets the reason, never silently dropped.

Measured against unified-planning's ``oversubscription[kairos]`` meta-engine and
Kairos' own oversubscription metric (tests/benchmarks/planning.py): those maximise a
sum of gains and say nothing about why a goal was left out; this works with every
engine, names a reason for each goal, and costs one call when all goals are reachable.
"""

from __future__ import annotations

import time
from collections import defaultdict
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, replace

from executive.bus.wording import seconds
from executive.planning.expression import And
from executive.planning.goals import GoalSpec
from executive.planning.planner import Planner, PlanningTask, PlanResult, PlanStatus


@dataclass(frozen=True)
class GoalPlan:
    """The best plan found, the goals it reaches, and why each other goal is left out."""

    result: PlanResult
    planned: tuple[int, ...] = ()
    unreachable: dict[int, str] = field(default_factory=dict)
    calls: int = 1

    @property
    def ok(self) -> bool:
        return self.result.ok


def by_priority(goals: Sequence[GoalSpec]) -> list[GoalSpec]:
    return sorted(goals, key=lambda g: (-g.priority, g.id))


def plan_goals(planner: Planner, task: PlanningTask, budget: float | None = None) -> GoalPlan:
    """Plan for a task's goals, or for the best subset of them by priority.

    ``budget`` bounds the whole search (seconds, default: the planner's timeout); each
    call gets what is left of it.
    """
    began = time.monotonic()
    budget = planner.timeout if budget is None else budget
    goals = by_priority(task.goals)
    # an engine may search until its timeout when no plan exists: leave time for subsets
    first = planner.solve(task, timeout=budget if len(goals) < 2 else budget / 2)
    if first.ok or not goals:
        return GoalPlan(first, tuple(g.id for g in goals))
    if not first.status.no_plan and first.status is not PlanStatus.TIMEOUT:
        reason = first.reason  # the engine cannot plan at all: every goal shares the reason
        return GoalPlan(first, (), {g.id: reason for g in goals})
    kept: list[GoalSpec] = []
    best: PlanResult | None = None
    unreachable: dict[int, str] = {}
    calls = 1
    for n, goal in enumerate(goals):
        left = budget - (time.monotonic() - began)
        if left <= 0.05:
            unreachable[goal.id] = f"planning ran out of time ({budget:g} s)"
            continue
        share = left / (len(goals) - n)  # each goal left gets a fair share of the time
        attempt = planner.solve(replace(task, goals=(*kept, goal)), timeout=share)
        calls += 1
        if attempt.ok:
            kept.append(goal)
            best = attempt
        else:
            unreachable[goal.id] = unreachable_reason(goal, kept, attempt)
    result = best or first
    return GoalPlan(result, tuple(g.id for g in kept), unreachable, calls)


def missing_for(goal: GoalSpec, result: PlanResult) -> list[str]:
    """Return the lines of a result's ``missing`` about parts of this goal."""
    parts = goal.expression.args if isinstance(goal.expression, And) else (goal.expression,)
    heads = tuple(f"{p} " for p in parts)
    return [line for line in result.missing if line.startswith(heads)]


def unreachable_reason(goal: GoalSpec, kept: Sequence[GoalSpec], attempt: PlanResult) -> str:
    """Say why no plan reaches a goal together with the ``kept`` ones: what it misses, if the
    relaxed reachability check tells, else the engine's answer or the goals in the way."""
    by = (
        f" by its deadline ({seconds(goal.deadline)} from now)" if goal.deadline is not None else ""
    )
    missing = missing_for(goal, attempt)
    if missing:  # nothing can make part of it true: the other goals do not matter
        return f"no plan reaches it{by} from the current state: {'; '.join(missing)} ({attempt.reason})"
    if not attempt.status.no_plan:
        return attempt.reason + (
            f" (with goals {', '.join(str(g.id) for g in kept)})" if kept else ""
        )
    if not kept:
        return f"no plan reaches it{by} from the current state ({attempt.reason})"
    others = ", ".join(str(g.id) for g in kept)
    plural = "s" if len(kept) > 1 else ""
    return f"no plan reaches it{by} together with goal{plural} {others} (kept first by priority)"


def blocked_note(blocked: Mapping[str, str]) -> str:
    """``"; cannot run now: call_lift, ride_lift (lift_link is ...)"`` or nothing."""
    if not blocked:
        return ""
    actions: defaultdict[str, list[str]] = defaultdict(list)
    for action, why in sorted(blocked.items()):
        actions[why].append(action)
    return "; cannot run now: " + "; ".join(f"{', '.join(a)} ({why})" for why, a in actions.items())
