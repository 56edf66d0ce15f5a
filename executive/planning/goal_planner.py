"""The goal planner (thesis 5.1.2, Figure 5.3): plan for every open goal, and own the
goals' states.

It wakes when a goal is added or cancelled and when the plan executor asks for a new
plan. Each round it pauses the executor (interruptible tasks pause, critical ones
finish first), reads the open goals and the facts again from the knowledge base, plans
for all goals (or the best subset by priority, see
:mod:`executive.planning.oversubscription`), validates and stores the plan, marks the
goals planned or unreachable with the reason, and hands the plan to the executor. A
goal that already holds is achieved without planning; one whose deadline passed fails.
A goal fails once ``max_attempts`` plans for it have failed. Actions whose task cannot
run (its behavior or every provider of a capability it needs is permanently faulty)
are left out of the problem, and a goal that needs them is unreachable with that reason.
When the world changes, unreachable goals are looked at again and maintenance goals
that stopped holding are re-posted (:mod:`executive.planning.goal_keeper`).

When to plan again: when asked to (a plan failed, a goal was cancelled, a robot was lost)
or when a goal is open that the running plan was not made for (added, or pending again).
A goal of the plan that ends (achieved, or failed) leaves the plan to the others: it
still serves them. Any other wake-up (a fact changed, a sensor's reading) only looks.
A round's reason is what asked for it, and what changed among the goals
(``goal 7 added``), never a wake-up that merely came first.

One owner: the goal planner's thread is the only thread that changes the state of a
goal or a plan. Its rounds mark goals; a cancel (:meth:`GoalPlanner.cancel`) and the
plan executor's reports (a plan executing, ended or failed; a goal executing, achieved
or past its deadline) are posted to it and applied in order. That thread never waits
long: pausing the executor (which waits for critical tasks) and the search for a plan
run on a second thread, whose results come back to it as jobs. So a cancel takes
effect at once, also while a plan is being computed, and a search that included a goal
cancelled meanwhile is thrown away and done again without it: a cancelled goal is never
planned or executed afterwards. A plan none of whose goals is open any more (its last
goal cancelled), or for which a round finds no successor, is cancelled at once and its
steps under way with it (critical ones too: nobody wants what they do any more).
:meth:`GoalPlanner.status` answers from a snapshot.
"""

from __future__ import annotations

import logging
import threading
import time
from collections import Counter
from collections.abc import Callable, Collection, Mapping, Sequence
from dataclasses import dataclass, field, replace

from executive.bus.reports import PlannerStatus, RoundPhase
from executive.bus.worker import Worker
from executive.planning.expression import Signature, WorldState
from executive.planning.goal_keeper import GoalKeeper, KeeperLinks
from executive.planning.goals import GoalSpec, RefusalCause, specs
from executive.planning.oversubscription import GoalPlan, blocked_note, plan_goals
from executive.planning.plan_executor import PlanExecutor
from executive.planning.planner import Planner, PlanningTask, PlanResult
from executive.planning.problem import live_world
from executive.planning.state_change import Change, GoalChange, apply_change
from knowledge.domain import DomainInfo
from knowledge.errors import DuraError, KnowledgeError
from knowledge.knowledge_base import KnowledgeBase
from knowledge.records import Fact, Goal, GoalState, PlanState

__all__ = ["GoalPlanner", "PlannerStatus", "RoundPhase"]  # the status records live in the bus API

log = logging.getLogger("dura.goal_planner")

CANCEL_WAIT = 10.0  # seconds a cancel waits for the goal planner's thread to take it up
PAUSE_SLICE = 0.5  # seconds between looks at a stop while critical tasks finish


@dataclass
class _Round:
    """A planning round under way (the goal planner's thread only)."""

    reason: str
    blocked: dict[str, str]
    goals: tuple[int, ...]
    began: float = field(default_factory=time.time)
    phase: RoundPhase = RoundPhase.PAUSING
    unreachable: dict[int, str] = field(default_factory=dict)


def _news(goal: Goal) -> str:
    """What made an open goal one the plan does not serve: ``goal 7 added``, ``goal 3:
    reachable again after ...`` (pending again, with the reason); nothing for a goal
    planned by an earlier process or round (a restart, a round that failed)."""
    if goal.state is not GoalState.PENDING:
        return ""
    if goal.reason:
        return f"goal {goal.id}: {goal.reason}"
    return f"goal {goal.id} added" + ("" if goal.source == "user" else f" ({goal.source})")


class GoalPlanner:
    """Plans for the open goals whenever :meth:`wake` is called, on its own thread
    after :meth:`start` (see the module docstring).

    It takes over the goal and plan state changes ``executor`` reports.
    """

    def __init__(
        self,
        kb: KnowledgeBase,
        domain: DomainInfo,
        planner: Planner,
        executor: PlanExecutor,
        *,
        max_attempts: int = 5,
        pause_timeout: float | None = None,
        blocked: Callable[[], Mapping[str, str]] | None = None,
        unavailable: Callable[[], Collection[str]] | None = None,
    ) -> None:
        self.kb = kb
        self.domain = domain
        self.planner = planner
        self.executor = executor
        self.max_attempts = max_attempts
        self.pause_timeout = pause_timeout
        self.blocked = blocked or dict  # action -> why its task cannot run now
        self.unavailable = unavailable or tuple  # objects that cannot act now
        self._worker = Worker("goal planner", after_each=self._after_each)
        self._search = Worker("goal planner's search")
        self._stopping = threading.Event()
        # the goal planner's thread only:
        self._failures: Counter[int] = Counter()  # failed plans per goal
        self._planned: frozenset[int] | None = None  # the goals the running plan serves
        self._replan = False
        self._reasons: list[str] = []  # why a replan was asked
        self._round: _Round | None = None
        self._snapshot = PlannerStatus()
        self._keeper = GoalKeeper(
            kb,
            domain,
            planner,
            KeeperLinks(
                post=self._worker.post,
                search=self._search.post,
                want=lambda reason: self._want(reason, False),
                planning_facts=executor.planning_facts,
                blocked=self.blocked,
                unavailable=self.unavailable,
            ),
            executor.clock,
        )
        executor.report_to(self._reported)

    # --- lifecycle ----------------------------------------------------------------------

    def start(self) -> None:
        if not self._worker.running:
            self._stopping.clear()
            self._worker.start()
            self._search.start()
            self.wake("the executive started", replan=True)

    def stop(self) -> None:
        """Stop planning: a search under way ends first (within the planner's timeout)."""
        if self._worker.running:
            self._stopping.set()
            self._keeper.stop()
            self._search.stop()
            self._worker.stop()

    def status(self) -> PlannerStatus:
        """What the goal planner is doing; never waits for its thread."""
        return self._snapshot

    def _after_each(self) -> None:
        r = self._round
        self._snapshot = PlannerStatus(
            planning=r is not None,
            phase=None if r is None else r.phase,
            reason="" if r is None else r.reason,
            goals=() if r is None else r.goals,
            since=None if r is None else r.began,
            planned=tuple(sorted(self._planned or ())),
        )

    # --- what others ask (any thread) -----------------------------------------------------

    def wake(self, reason: str, *, replan: bool = False) -> None:
        """Plan again soon if a goal is open that the plan does not serve; ``replan``:
        plan again anyway, for ``reason``.

        Without ``replan`` the round's reason is what changed among the goals (``goal 7
        added``), not ``reason``: a wake-up that merely came first is not why.
        """
        self._worker.post(lambda: self._want(reason, replan))

    def world_changed(self, reason: str) -> None:
        """The world changed outside the plan (a user, a component or a sensing rule set
        a fact or an object; a component was reset or repaired): look again at
        unreachable goals, and at maintenance goals."""
        self._worker.post(lambda: self._keeper.changed(reason, outside=True))

    def facts_changed(self, reason: str) -> None:
        """Facts changed, the plan's own steps included: re-post the maintenance goals
        that no longer hold."""
        self._worker.post(lambda: self._keeper.changed(reason, outside=False))

    def replan(self, reason: str) -> None:
        """The executor's ``on_replan`` callback: the current plan failed."""
        self._worker.post(lambda: self._plan_failed(reason))

    def cancel(self, goal_id: int, timeout: float = CANCEL_WAIT) -> Goal:
        """Cancel an open goal and plan for the others; returns the cancelled goal.

        Raises:
            KnowledgeError: no such goal, or it is not open (``goal 3 is achieved already``).
            DuraError: the goal planner did not take the cancel up within ``timeout``
                seconds; it stays queued and takes effect when the thread is free.
        """
        done = threading.Event()
        answer: list[Goal | Exception] = []

        def job() -> None:
            try:
                answer.append(self._cancel(goal_id))
            except Exception as e:  # handed to the caller
                answer.append(e)
            finally:
                done.set()

        self._worker.post(job)
        if not done.wait(timeout):
            raise DuraError(
                f"goal {goal_id}: the goal planner is busy; the cancel is queued and "
                "takes effect as soon as it is free"
            )
        if isinstance(answer[0], Exception):
            raise answer[0]
        return answer[0]

    def _reported(self, change: Change) -> None:
        """A goal or plan state change the executor saw (on its thread): apply it here."""
        self._worker.post(lambda: self._apply(change))

    # --- the goal planner's thread --------------------------------------------------------

    def _apply(self, change: Change) -> None:
        applied = apply_change(self.kb, change)
        if applied and isinstance(change, GoalChange) and not change.state.is_open:
            # the plan goes on for the others: an ended goal is no reason to replace it
            self._planned = (self._planned or frozenset()) - {change.goal}

    def _cancel(self, goal_id: int) -> Goal:
        goal = self.kb.goal(goal_id)
        if not goal.state.can_become(GoalState.CANCELLED, keep=goal.keep):
            raise KnowledgeError(f"goal {goal.id} is {goal.state.value} already")
        was_open = goal.state.is_open
        goal = self.kb.set_goal_state(goal_id, GoalState.CANCELLED)
        plan = self.kb.latest_plan()
        if (
            was_open
            and plan is not None
            and goal_id in plan.goal_ids
            and not any(self.kb.goal(g).state.is_open for g in plan.goal_ids)
        ):
            self._end_plan(f"goal {goal_id} cancelled: no goal of the plan is open")
        if self._round is None and was_open:
            self._want(f"goal {goal_id} cancelled", replan=True)
        # else the round under way reads the goals after its pause and looks at them
        # again after its search: it leaves the cancelled goal out, no new round needed
        return goal

    def _plan_failed(self, reason: str) -> None:
        for goal_id in self._planned or ():
            self._failures[goal_id] += 1
        self._want(reason, replan=True)

    def _want(self, reason: str, replan: bool) -> None:
        if replan:
            self._reasons.append(reason)
            self._replan = True
        self._begin()

    def _begin(self) -> None:
        """Begin a round if one was asked for or a goal is open that the plan does not
        serve, and none is under way."""
        if self._round is not None or self._stopping.is_set():
            return  # a round under way looks again when it ends
        goals = self.kb.open_goals()
        open_ids = frozenset(g.id for g in goals)
        planned = self._planned or frozenset()
        news = [_news(g) for g in goals if g.id not in planned]
        if not (self._replan and (open_ids or planned)) and not news:
            # nothing asked, and the plan serves every open goal (an ended one is no
            # reason to replace it)
            self._planned, self._replan, self._reasons = open_ids, False, []
            return
        reasons, self._reasons, self._replan = self._reasons, [], False
        reason = "; ".join(dict.fromkeys(r for r in (*reasons, *news) if r)) or "asked to plan"
        blocked = dict(self.blocked())
        self.kb.log_event(
            "PLANNING",
            "goal planner",
            {"reason": reason, "goals": sorted(open_ids), "blocked": sorted(blocked)},
        )
        round_ = self._round = _Round(reason, blocked, tuple(sorted(open_ids)))
        self._search.post(self._step(round_, lambda: self._pause(round_)))

    def _decide(self, round_: _Round, facts: list[Fact]) -> None:
        """Settle what needs no plan (achieved, failed, unusable goals); search for the rest."""
        if self._stopping.is_set():
            return
        objects = self.kb.objects()
        usable, refused = specs(
            self.kb.open_goals(), Signature.of(self.domain, objects), clock=self.executor.clock
        )
        failed: dict[int, str] = {}
        for goal_id, refusal in refused.items():
            if refusal.cause is RefusalCause.DEADLINE_PASSED:
                failed[goal_id] = refusal.reason
            else:
                round_.unreachable[goal_id] = refusal.reason
        state, now = WorldState(facts), WorldState(self.kb.facts())
        achieved = [g.id for g in usable if self._keeper.achieved_at_once(g, state, now)]
        todo = []
        for g in usable:
            if g.id in achieved:
                continue
            if self._failures[g.id] >= self.max_attempts:
                failed[g.id] = (
                    f"{self.max_attempts} plans for it failed, the last because {round_.reason}"
                )
            else:
                todo.append(g)
        for goal_id in achieved:
            self.kb.set_goal_state(goal_id, GoalState.ACHIEVED)
        for goal_id, why in failed.items():
            self.kb.set_goal_state(goal_id, GoalState.FAILED, why)
        if not todo:
            self._conclude(round_, None, ())
            return
        world = live_world(objects, facts, self.kb, self.executor.clock, self.unavailable())
        task = PlanningTask(self.domain.path, world, tuple(todo), frozenset(round_.blocked))
        round_.phase = RoundPhase.SEARCHING
        self._search.post(self._step(round_, lambda: self._solve(round_, task)))

    def _solved(self, round_: _Round, task: PlanningTask, outcome: GoalPlan) -> None:
        """Store, mark and hand over the plan, unless a goal it searched for was cancelled
        during the search: then search again without it."""
        if self._stopping.is_set():
            return
        cancelled = [g.id for g in task.goals if self.kb.goal(g.id).state is GoalState.CANCELLED]
        if cancelled:
            left = tuple(g for g in task.goals if g.id not in cancelled)
            self.kb.log_event(
                "PLANNING",
                "goal planner",
                {
                    "reason": f"goals {', '.join(map(str, cancelled))} cancelled while planning",
                    "goals": [g.id for g in left],
                    "blocked": sorted(round_.blocked),
                },
            )
            if left:
                again = replace(task, goals=left)
                self._search.post(self._step(round_, lambda: self._solve(round_, again)))
            else:
                self._conclude(round_, None, ())
            return
        round_.unreachable.update(
            {g: why + blocked_note(round_.blocked) for g, why in outcome.unreachable.items()}
        )
        planned = outcome.planned if outcome.ok else ()
        self._conclude(round_, outcome.result, [g for g in task.goals if g.id in planned])

    def _conclude(
        self, round_: _Round, result: PlanResult | None, planned: Sequence[GoalSpec]
    ) -> None:
        open_now = {g.id for g in self.kb.open_goals()}
        # a goal that ended during the search (achieved as the paused plan finished a
        # critical step, past its deadline) is not planned again
        planned = [g for g in planned if g.id in open_now]
        plan_id = None
        if planned and result is not None and result.plan is not None:
            ids = [g.id for g in planned]
            plan_id = self.kb.store_plan(
                result.plan.records(), engine=result.engine, goal_ids=ids
            ).id
            for goal_id in ids:
                self.kb.set_goal_state(goal_id, GoalState.PLANNED)
        for goal_id, why in round_.unreachable.items():
            if goal_id in open_now:
                self.kb.set_goal_state(goal_id, GoalState.UNREACHABLE, why)
        if plan_id is not None and result is not None and result.plan is not None:
            self.executor.execute(result.plan, plan_id, planned)
        else:
            self._end_plan("no plan for the open goals" if open_now else "no goal is open")
        self._planned = frozenset(g.id for g in planned)
        self._round = None
        self._begin()  # what was asked while the round was under way

    def _end_plan(self, reason: str) -> None:
        """End the plan being executed at once: cancelled (unless it ended already), its
        steps under way cancelled and their at-start effects taken back."""
        plan = self.kb.latest_plan()
        if plan is not None and plan.state in (PlanState.PENDING, PlanState.EXECUTING):
            self.kb.set_plan_state(plan.id, PlanState.CANCELLED, reason)
        self.executor.abandon(reason)

    def _step(self, round_: _Round, step: Callable[[], None]) -> Callable[[], None]:
        """A job of a round, on either thread: a round that fails is over (logged), and
        the next wake plans again, as it would after a round that ended."""

        def job() -> None:
            try:
                step()
            except Exception:
                log.exception("planning round failed (%s)", round_.reason)
                self._worker.post(lambda: self._forget(round_))

        return job

    def _forget(self, round_: _Round) -> None:
        if self._round is round_:
            self._round = None

    # --- the search thread ----------------------------------------------------------------

    def _pause(self, round_: _Round) -> None:
        """Pause the executor (critical tasks finish first) and read the facts to plan from."""
        limit = None if self.pause_timeout is None else time.monotonic() + self.pause_timeout
        while not self._stopping.is_set():
            left = PAUSE_SLICE if limit is None else min(PAUSE_SLICE, limit - time.monotonic())
            if self.executor.pause(max(0.0, left)):
                break
            if limit is not None and time.monotonic() >= limit:
                break  # plan anyway: the tasks still running are in the facts
        if self._stopping.is_set():
            return
        facts = self.executor.planning_facts()
        self._worker.post(self._step(round_, lambda: self._decide(round_, facts)))

    def _solve(self, round_: _Round, task: PlanningTask) -> None:
        if self._stopping.is_set():
            return
        outcome = plan_goals(self.planner, task)
        self._worker.post(self._step(round_, lambda: self._solved(round_, task, outcome)))
