"""A dry run (PlanSys2's "get plan"): what the planner would do now, without doing it.

It plans for the open goals, and for goal expressions asked about as if they were added
now, from the state the goal planner would plan from (the knowledge base's facts, with
the at-start effects of paused steps undone), without the actions that cannot run now,
with the same engine and the same choice of goals by priority, and changes nothing: no
goal stored, no goal or plan state, no event, no pause of the plan under way. Its search
waits for the goal planner's (one engine, one worker).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

from executive.bus.api.planning import DryRunReply, PlannedStep, StepAfter
from executive.bus.clock import Clock
from executive.planning.expression import Signature, WorldState, parse
from executive.planning.goals import normalized, specs
from executive.planning.oversubscription import blocked_note, plan_goals
from executive.planning.partial_order import PartialOrderPlan
from executive.planning.planner import Planner, PlanningTask
from executive.planning.problem import live_world
from knowledge.domain import DomainInfo
from knowledge.knowledge_base import KnowledgeBase
from knowledge.records import Fact, Goal
from knowledge.transitions import GoalState


def dry_run(
    kb: KnowledgeBase,
    domain: DomainInfo,
    planner: Planner,
    facts: Sequence[Fact],
    blocked: Mapping[str, str],
    *,
    clock: Clock,
    timeout: float | None = None,
    asked: Sequence[str] = (),
) -> DryRunReply:
    """Plan for the open goals and the goals ``asked`` about (ids -1, -2, ...: nothing is
    stored) on the live state; nothing is executed.

    Raises:
        DomainError: a goal asked about does not fit the domain and objects.
    """
    objects = kb.objects()
    signature = Signature.of(domain, objects)
    asked = [normalized(text) for text in asked]
    for text in asked:
        parse(text, signature)
    open_goals = kb.open_goals() + [
        Goal(-n, text, GoalState.PENDING) for n, text in enumerate(asked, 1)
    ]
    usable, refused = specs(open_goals, signature, clock=clock)
    unreachable = {str(i): r.reason for i, r in refused.items()}
    state = WorldState(facts)
    achieved = [g.id for g in usable if state.holds(g.expression)]
    todo = tuple(g for g in usable if g.id not in achieved)
    ids = [g.id for g in open_goals]
    if not todo:
        why = "no open goal needs a plan" if ids else "no open goals"
        return DryRunReply("nothing_to_do", planner.engine, 0.0, why, ids, [], achieved,
                           unreachable, [], None, asked)  # fmt: skip
    world = live_world(objects, facts, kb, clock)
    task = PlanningTask(domain.path, world, todo, frozenset(blocked))
    outcome = plan_goals(planner, task, timeout)
    note = blocked_note(blocked)
    unreachable.update({str(i): why + note for i, why in outcome.unreachable.items()})
    result = outcome.result
    plan = result.plan if outcome.ok else None
    return DryRunReply(
        status=result.status.value,
        engine=result.engine,
        time=round(result.time, 4),
        reason=result.reason,
        goals=ids,
        planned=list(outcome.planned) if outcome.ok else [],
        achieved=achieved,
        unreachable=unreachable,
        steps=planned_steps(plan),
        makespan=plan.makespan if plan is not None else None,
        asked=asked,
    )


def planned_steps(plan: PartialOrderPlan | None) -> list[PlannedStep]:
    """A plan's steps, as ``dura plan --offline --json`` prints them."""
    return [
        PlannedStep(
            s.index,
            s.action,
            tuple(s.args),
            s.start,
            s.duration,
            tuple(StepAfter(p.step, p.at.value) for p in s.after),
        )
        for s in (plan.steps if plan is not None else ())
    ]
