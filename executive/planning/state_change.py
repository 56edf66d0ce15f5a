"""Goal and plan state changes the plan executor reports to their owner.

The goal planner's thread is the one writer of goal and plan states. The plan executor
runs on a thread of its own, so it never writes them: it reports what it saw (a plan
started, ended or failed; a goal executing, achieved, or past its deadline) as a
:class:`GoalChange` or :class:`PlanChange`, and the owner applies it with
:func:`apply_change` in the order reported. By then the owner may have changed the row
itself (cancelled the goal, superseded the plan); a change its state machine no longer
allows is stale and dropped.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass

from knowledge.knowledge_base import KnowledgeBase
from knowledge.records import GoalState, PlanState

log = logging.getLogger("dura.plan_executor")


@dataclass(frozen=True)
class GoalChange:
    """A goal of the plan being executed reached ``state`` (with the reason)."""

    goal: int
    state: GoalState
    reason: str = ""


@dataclass(frozen=True)
class PlanChange:
    """The plan being executed reached ``state`` (with the reason)."""

    plan: int
    state: PlanState
    reason: str = ""


Change = GoalChange | PlanChange


def apply_change(kb: KnowledgeBase, change: Change) -> bool:
    """Write a reported change unless it is stale; whether it was written.

    Call it on the thread that owns goal and plan states: the check and the write are
    one decision only there.
    """
    if isinstance(change, GoalChange):
        goal = kb.goal(change.goal)
        if not goal.state.can_become(change.state, keep=goal.keep):
            log.debug("goal %d is %s: %s is stale", goal.id, goal.state.value, change)
            return False
        kb.set_goal_state(change.goal, change.state, change.reason)
        return True
    plan = kb.plan(change.plan)
    if not plan.state.can_become(change.state):
        log.debug("plan %d is %s: %s is stale", plan.id, plan.state.value, change)
        return False
    kb.set_plan_state(change.plan, change.state, change.reason)
    return True
