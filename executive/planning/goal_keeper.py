"""Goals that keep up with the world, on the goal planner's thread.

The goal planner (:mod:`executive.planning.goal_planner`) owns goal states; this part
of it changes them when the world changes, with the timing of
:class:`~executive.planning.goal_watch.GoalWatch`:

- An unreachable goal is looked at again after a change outside the plan (a fact or
  object set by a user, a component or a sensing rule; a component reset or repaired):
  the planner searches for it alone, from the facts the goal planner would plan from,
  without pausing the plan under way. If a plan reaches it, the goal is pending again
  (re-posted, with the reason) and the next round plans for it with the others; if
  not, it stays unreachable, with the new reason if the reason changed.
- A maintenance goal that is achieved and no longer holds (whoever changed the facts,
  the plan's own steps included) is pending again: re-posted, so the next round plans
  to make it hold again.
"""

from __future__ import annotations

import logging
import time
from collections.abc import Callable, Collection, Mapping
from dataclasses import dataclass

from executive.bus.clock import Clock
from executive.bus.timers import Timer, later
from executive.planning.expression import Signature, WorldState
from executive.planning.goal_watch import GoalWatch
from executive.planning.goals import GoalSpec, specs
from executive.planning.oversubscription import blocked_note, unreachable_reason
from executive.planning.planner import Planner, PlanningTask, PlanResult
from executive.planning.problem import live_world
from knowledge.domain import DomainInfo
from knowledge.knowledge_base import KnowledgeBase
from knowledge.records import Fact, GoalState

log = logging.getLogger("dura.goal_planner")

LOOK_TIMEOUT = 10.0  # seconds the planner may search for one unreachable goal on a look


@dataclass(frozen=True)
class KeeperLinks:
    """How the keeper reaches the goal planner's threads and the plan executor.

    Args:
        post: run a job on the goal planner's thread.
        search: run a job on the search thread (it may wait for the planner).
        want: ask the goal planner for a round, with the reason.
        planning_facts: the facts the goal planner plans from (any thread).
        blocked: the actions that cannot run now, and why.
        unavailable: the objects that cannot act now.
    """

    post: Callable[[Callable[[], None]], None]
    search: Callable[[Callable[[], None]], None]
    want: Callable[[str], None]
    planning_facts: Callable[[], list[Fact]]
    blocked: Callable[[], Mapping[str, str]]
    unavailable: Callable[[], Collection[str]] = tuple


class GoalKeeper:
    """Looks again at unreachable goals and re-posts broken maintenance goals."""

    def __init__(
        self,
        kb: KnowledgeBase,
        domain: DomainInfo,
        planner: Planner,
        links: KeeperLinks,
        clock: Clock,
        *,
        watch: GoalWatch | None = None,
    ) -> None:
        self.kb = kb
        self.domain = domain
        self.planner = planner
        self.links = links
        self.clock = clock
        self.watch = watch or GoalWatch()
        self._looking = False  # a look is on the search thread
        self._reason = ""  # the latest change outside the plan
        self._timer: Timer | None = None
        self._stopped = False

    def stop(self) -> None:
        """Stop looking (a pending timer is cancelled)."""
        self._stopped = True
        if self._timer is not None:
            self._timer.cancel()

    # --- the goal planner's thread -------------------------------------------------------

    def changed(self, reason: str, *, outside: bool) -> None:
        """Take a change of facts; ``outside``: not by the plan (a user, a component, sensing, a
        repair), so unreachable goals may be reachable now."""
        if self._stopped:
            return
        self._repost_broken(reason)
        if outside:
            self._reason = reason
            self.watch.world_changed(g.id for g in self.kb.goals([GoalState.UNREACHABLE]))
        self._look()

    def achieved_at_once(self, spec: GoalSpec, planning: WorldState, facts: WorldState) -> bool:
        """Tell whether a goal holds, so that it needs no plan: in the facts the planner plans
        from, and for a maintenance goal also in the facts as they are (a paused step
        may have taken it away already)."""
        if not planning.holds(spec.expression):
            return False
        return not self.kb.goal(spec.id).keep or facts.holds(spec.expression)

    def _repost_broken(self, reason: str) -> None:
        kept = self.kb.kept_goals()
        if not kept:
            return
        usable, _ = specs(kept, Signature.of(self.domain, self.kb.objects()), clock=self.clock)
        expressions = {s.id: s.expression for s in usable}
        now = time.monotonic()
        for goal in self.watch.broken(kept, expressions, WorldState(self.kb.facts())):
            later = self.watch.may_repost(goal.id, now)
            if later is not None:
                self._wake_at(later)
                continue
            self.watch.reposted(goal.id, now)
            why = f"maintenance goal: {goal.expression} no longer holds" + (
                f" ({reason})" if reason else ""
            )
            self.kb.set_goal_state(goal.id, GoalState.PENDING, why)
            self.links.want(f"goal {goal.id} no longer holds")

    def _look(self) -> None:
        """Look at the unreachable goals that are due (one look at a time)."""
        if self._looking or self._stopped:
            return
        goals = {g.id: g for g in self.kb.goals([GoalState.UNREACHABLE])}
        due, later = self.watch.due(goals, time.monotonic())
        if later is not None:
            self._wake_at(later)
        if not due:
            return
        usable, _ = specs(
            [goals[i] for i in due], Signature.of(self.domain, self.kb.objects()), clock=self.clock
        )
        for left in set(due) - {s.id for s in usable}:  # an object is gone, a deadline passed
            self.watch.looked(left, time.monotonic())
        if not usable:
            return
        self._looking = True
        reason, objects = self._reason, self.kb.objects()
        self.links.search(lambda: self._search(usable, objects, reason))

    def _looked(
        self,
        results: dict[int, tuple[GoalSpec, PlanResult]],
        blocked: Mapping[str, str],
        reason: str,
    ) -> None:
        self._looking = False
        now = time.monotonic()
        for goal_id, (spec, result) in results.items():
            goal = self.kb.goal(goal_id)
            if goal.state is not GoalState.UNREACHABLE:
                continue  # cancelled meanwhile
            self.watch.looked(goal_id, now)
            if result.ok:
                why = f"reachable again after {reason}" if reason else "reachable again"
                self.kb.set_goal_state(goal_id, GoalState.PENDING, why)
                self.links.want(f"goal {goal_id} is reachable again")
                continue
            why = unreachable_reason(spec, (), result) + blocked_note(blocked)
            if why != goal.reason:
                self.kb.set_goal_state(goal_id, GoalState.UNREACHABLE, why)
        self._look()

    def _wake_at(self, when: float) -> None:
        """Look again at ``when`` (monotonic seconds): one timer at a time."""
        if self._timer is not None:
            self._timer.cancel()
        self._timer = later(
            when - time.monotonic(),
            lambda: self.links.post(lambda: self.changed("", outside=False)),
        )

    # --- the search thread --------------------------------------------------------------

    def _search(self, goals: list[GoalSpec], objects: dict[str, str], reason: str) -> None:
        results: dict[int, tuple[GoalSpec, PlanResult]] = {}
        blocked: dict[str, str] = {}
        try:
            facts = tuple(self.links.planning_facts())
            blocked = dict(self.links.blocked())
            unavailable = tuple(self.links.unavailable())
            timeout = min(self.planner.timeout, LOOK_TIMEOUT)
            for goal in goals:
                world = live_world(objects, facts, self.kb, self.clock, unavailable)
                task = PlanningTask(self.domain.path, world, (goal,), frozenset(blocked))
                results[goal.id] = (goal, self.planner.solve(task, timeout=timeout))
        except Exception:
            log.exception("looking again at unreachable goals failed")
        self.links.post(lambda: self._looked(results, blocked, reason))
