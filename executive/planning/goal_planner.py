"""The goal planner (thesis 5.1.2, Figure 5.3): plan for every open goal.

It wakes when a goal is added or cancelled and when the plan executer asks for a new
plan. Each round it pauses the executer (interruptible tasks pause, critical ones
finish first), reads the open goals and the facts again from the knowledge base,
plans for all goals (or the best subset by priority, see
:mod:`executive.planning.oversubscription`), validates and stores the plan, marks the goals
planned or unreachable with the reason, and hands the plan to the executer. A goal
that already holds is achieved without planning; one whose deadline passed fails.
A goal fails once ``max_attempts`` plans for it have failed. Actions whose task cannot
run (its behavior or every provider of a capability it needs is permanently faulty)
are left out of the problem, and a goal that needs them is unreachable with that reason.
"""

from __future__ import annotations

import logging
import threading
from collections import Counter, defaultdict
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field

from executive.planning.expression import Signature, WorldState
from executive.planning.goals import RefusalCause, specs
from executive.planning.oversubscription import plan_goals
from executive.planning.plan_executer import PlanExecuter
from executive.planning.planner import Planner, PlanningTask, PlanResult
from executive.planning.problem import World
from knowledge.domain import DomainInfo
from knowledge.knowledge_base import KnowledgeBase
from knowledge.records import GoalState

log = logging.getLogger("dura.goal_planner")


@dataclass(frozen=True)
class Round:
    """What one planning round did."""

    reason: str
    plan_id: int | None = None
    planned: tuple[int, ...] = ()
    achieved: tuple[int, ...] = ()
    unreachable: dict[int, str] = field(default_factory=dict)
    failed: dict[int, str] = field(default_factory=dict)
    result: PlanResult | None = None


class GoalPlanner:
    """Plans for the open goals whenever :meth:`wake` is called (on its own thread
    after :meth:`start`, or synchronously with :meth:`plan_now`)."""

    def __init__(
        self,
        kb: KnowledgeBase,
        domain: DomainInfo,
        planner: Planner,
        executer: PlanExecuter,
        *,
        max_attempts: int = 5,
        pause_timeout: float | None = None,
        blocked: Callable[[], Mapping[str, str]] | None = None,
    ) -> None:
        self.kb = kb
        self.domain = domain
        self.planner = planner
        self.executer = executer
        self.max_attempts = max_attempts
        self.pause_timeout = pause_timeout
        self.blocked = blocked or dict  # action -> why its task cannot run now
        self._failures: Counter[int] = Counter()  # failed plans per goal
        self._planned: frozenset[int] | None = None
        self._replan = True
        self._reasons: list[str] = []
        self._wake = threading.Event()
        self._stopping = False
        self._thread: threading.Thread | None = None
        self._lock = threading.Lock()

    # --- lifecycle ----------------------------------------------------------------------

    def start(self) -> None:
        if self._thread is None:
            self._stopping = False
            self._thread = threading.Thread(target=self._loop, name="goal-planner", daemon=True)
            self._thread.start()
            self.wake("the executive started")

    def stop(self) -> None:
        if self._thread is not None:
            self._stopping = True
            self._wake.set()
            self._thread.join()
            self._thread = None

    def wake(self, reason: str, *, replan: bool = False) -> None:
        """Plan again soon; ``replan`` even if the open goals did not change."""
        with self._lock:
            self._reasons.append(reason)
            self._replan = self._replan or replan
        self._wake.set()

    def replan(self, reason: str) -> None:
        """The executer's ``on_replan`` callback: the current plan failed."""
        with self._lock:
            for goal_id in self._planned or ():
                self._failures[goal_id] += 1
        self.wake(reason, replan=True)

    def cancel(self, goal_id: int) -> None:
        """Cancel an open goal and plan for the others."""
        self.kb.set_goal_state(goal_id, GoalState.CANCELLED)
        self.wake(f"goal {goal_id} cancelled", replan=True)

    def _loop(self) -> None:
        while True:
            self._wake.wait()
            self._wake.clear()
            if self._stopping:
                return
            try:
                self.plan_now()
            except Exception:  # a failed round must not stop the planner
                log.exception("planning round failed")

    # --- one round -----------------------------------------------------------------------

    def plan_now(self) -> Round | None:
        """Run one planning round if something changed; returns what it did."""
        with self._lock:
            reasons, self._reasons = self._reasons, []
            replan, self._replan = self._replan, False
        reason = "; ".join(dict.fromkeys(reasons)) or "asked to plan"
        open_ids = frozenset(g.id for g in self.kb.open_goals())
        if (not replan and open_ids == self._planned) or (not open_ids and not self._planned):
            self._planned = open_ids
            return None
        blocked = dict(self.blocked())
        self.kb.log_event(
            "PLANNING",
            "goal planner",
            {"reason": reason, "goals": sorted(open_ids), "blocked": sorted(blocked)},
        )
        self.executer.pause(self.pause_timeout)
        facts = self.executer.planning_facts()
        objects = self.kb.objects()
        usable, refused = specs(self.kb.open_goals(), Signature.of(self.domain, objects))
        failed: dict[int, str] = {}
        unreachable: dict[int, str] = {}
        for goal_id, refusal in refused.items():
            if refusal.cause is RefusalCause.DEADLINE_PASSED:
                failed[goal_id] = refusal.reason
            else:
                unreachable[goal_id] = refusal.reason
        state = WorldState(facts)
        achieved = tuple(g.id for g in usable if state.holds(g.expression))
        todo = []
        for g in usable:
            if g.id in achieved:
                continue
            if self._failures[g.id] >= self.max_attempts:
                failed[g.id] = f"{self.max_attempts} plans for it failed, the last because {reason}"
            else:
                todo.append(g)
        for goal_id in achieved:
            self.kb.set_goal_state(goal_id, GoalState.ACHIEVED)
        for goal_id, why in failed.items():
            self.kb.set_goal_state(goal_id, GoalState.FAILED, why)
        result = None
        plan_id = None
        planned: tuple[int, ...] = ()
        if todo:
            world = World(objects, tuple(facts))
            task = PlanningTask(self.domain.path, world, tuple(todo), frozenset(blocked))
            outcome = plan_goals(self.planner, task)
            result = outcome.result
            unreachable.update(
                {goal_id: why + _without(blocked) for goal_id, why in outcome.unreachable.items()}
            )
            planned = outcome.planned if outcome.ok else ()
            if outcome.ok and result.plan is not None:
                stored = self.kb.store_plan(
                    result.plan.records(), engine=result.engine, goal_ids=planned
                )
                plan_id = stored.id
                for goal_id in planned:
                    self.kb.set_goal_state(goal_id, GoalState.PLANNED)
        for goal_id, why in unreachable.items():
            self.kb.set_goal_state(goal_id, GoalState.UNREACHABLE, why)
        if plan_id is not None and result is not None and result.plan is not None:
            self.executer.execute(result.plan, plan_id, [g for g in todo if g.id in planned])
        else:
            self.executer.abandon()
        self._planned = frozenset(planned)
        return Round(reason, plan_id, planned, achieved, unreachable, failed, result)


def _without(blocked: Mapping[str, str]) -> str:
    """``"; cannot run now: call_lift, ride_lift (lift_link is ...)"`` or nothing."""
    if not blocked:
        return ""
    actions: defaultdict[str, list[str]] = defaultdict(list)
    for action, why in sorted(blocked.items()):
        actions[why].append(action)
    return "; cannot run now: " + "; ".join(f"{', '.join(a)} ({why})" for why, a in actions.items())
