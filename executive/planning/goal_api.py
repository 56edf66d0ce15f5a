"""The high level's goal verbs on the bus (:mod:`executive.bus.api.planning`): goals,
plans and dry runs, the domain, events and status.

``status``, ``goal/list``, ``plan/show`` and ``events`` answer at once, from the
knowledge base and the snapshots the plan executor and the goal planner keep: they never
wait behind a step being dispatched or a plan being computed, nor for the planner to
warm up. A request that needs the domain (a goal, a dry run, the domain) waits for the
high level to plan.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from typing import Any, TypeVar

from executive.bus.api import planning as api
from executive.bus.message import MAX_PAYLOAD, encode
from executive.bus.reports import DiagnosisInfo, ExecutionStatus, PlannerStatus
from executive.bus.schema import plain
from executive.bus.service import Context
from executive.bus.verb import Empty
from executive.planning.blocked_tasks import blocked_now
from executive.planning.deliberation import Deliberation
from executive.planning.domain_description import describe
from executive.planning.dry_run import dry_run
from executive.planning.goals import submit
from knowledge.errors import DuraError
from knowledge.records import Event, Goal, GoalState

SECTIONS = ("tasks", "components", "robots")  # what other services add to ``status``
MAX_EVENTS = 10_000  # the most events one request returns
HISTORY_PAGE = 1_000  # events read at a time for a goal's history
MAX_GOALS = 10_000  # the most goals one request reads
EVENTS_BUDGET = MAX_PAYLOAD * 3 // 4  # bytes of events (or goals) in one reply: under the limit
STATUS_GOALS_BUDGET = MAX_PAYLOAD // 4  # bytes of goals in ``status``, which carries more

R = TypeVar("R")


class GoalApi:
    """Serves goals, plans, the domain, events and status.

    Args:
        context: the robot, bus and knowledge base.
        planning: the high level at work, once it plans (waits for it; raises
            :class:`~knowledge.errors.DuraError` with the reason if it does not).
        current: the high level at work now, or ``None`` (never waits).
        diagnoses: the latest diagnosis result (``{}`` before the first).
        status: the sections other services add to ``status`` (``tasks`` from the task
            executor, ``components`` from the launcher), by name.
    """

    def __init__(
        self,
        context: Context,
        *,
        planning: Callable[[], Deliberation],
        current: Callable[[], Deliberation | None],
        diagnoses: Callable[[], dict[str, Any]],
        status: Mapping[str, Callable[[], Any]],
    ) -> None:
        self.context = context
        self.planning = planning
        self.current = current
        self.diagnoses = diagnoses
        self.extra_status = dict(status)
        unknown = sorted(set(self.extra_status) - set(SECTIONS))
        if unknown:
            raise ValueError(f"status has no section {', '.join(unknown)} (only {SECTIONS})")

    def serve(self) -> list[Any]:
        """Answer the verbs; returns the queryables."""
        bus = self.context.bus
        return [
            api.GOAL_ADD.serve(bus, self._goal_add),
            api.GOAL_LIST.serve(bus, self._goal_list),
            api.GOAL_SHOW.serve(bus, self._goal_show),
            api.GOAL_CANCEL.serve(bus, self._goal_cancel),
            api.PLAN_SHOW.serve(bus, self._plan_show),
            api.PLAN_DRY_RUN.serve(bus, self._plan_dry_run),
            api.DOMAIN_SHOW.serve(bus, self._domain_show),
            api.EVENTS.serve(bus, self._events),
            api.STATUS.serve(bus, self._status),
        ]

    def _goal_add(self, request: api.GoalAdd) -> api.GoalReply:
        planning = self.planning()
        goal = submit(
            self.context.kb,
            planning.domain,
            request.expression,
            priority=request.priority,
            deadline=request.deadline,
            source=request.source,
            keep=request.keep,
        )
        planning.goals.wake(f"goal {goal.id} added")
        return api.GoalReply(goal)

    def _goal_list(self, request: api.GoalQuery) -> api.GoalsReply:
        """The newest goals asked for that fit in a reply: at most :data:`MAX_GOALS` are
        read, and one more tells whether there are older ones."""
        wanted = MAX_GOALS if request.limit is None else min(request.limit, MAX_GOALS)
        goals = self.context.kb.goals(request.states, before=request.before, limit=wanted + 1)
        asked = len(goals) if request.limit is None else min(len(goals), request.limit)
        kept = fitting(goals[-wanted:] if wanted else [], newest=True)
        return api.GoalsReply(kept, more=True if len(kept) < asked else None)

    def _goal_show(self, request: api.GoalId) -> api.GoalHistory:
        kb = self.context.kb
        goal = kb.goal(request.id)
        subject = f"goal {goal.id}"
        first = kb.first_event(subject)
        events: list[Event] = []
        after = first - 1 if first is not None else None
        while after is not None:  # page by page from the goal's first event: the log is long
            page = kb.events(after=after, limit=HISTORY_PAGE, oldest=True)
            events += [e for e in page if e.subject == subject or _names_goal(e, goal.id)]
            after = page[-1].id if len(page) == HISTORY_PAGE else None
        return api.GoalHistory(goal, fitting(events, newest=False))

    def _goal_cancel(self, request: api.GoalId) -> api.GoalReply:
        """Cancelled by the goal planner's thread, which owns goal states; the reply is
        the goal as it left that thread (or the reason it could not be cancelled)."""
        planning = self.planning()
        return api.GoalReply(planning.goals.cancel(request.id))

    def _plan_show(self, request: Empty) -> api.PlanReply:
        plan = self.context.kb.latest_plan()
        current = self.current()
        robots: list[str] | None = None
        if plan is not None and current is not None:
            runner = current.executor.runner
            found = [runner.performer(s.action, s.args) for s in plan.steps]
            robots = [r or "" for r in found] if any(found) else None
        return api.PlanReply(plan, self._execution(), robots)

    def _plan_dry_run(self, request: api.DryRun) -> api.DryRunReply:
        """Plan for the open goals and those asked about on the live state; nothing
        changes."""
        planning = self.planning()
        return dry_run(
            self.context.kb,
            planning.domain,
            planning.planner,
            planning.executor.planning_facts(),
            blocked_now(self.context.kb, self.context.robot),
            clock=planning.executor.clock,
            timeout=request.timeout,
            asked=request.goals,
        )

    def _domain_show(self, request: Empty) -> api.DomainReply:
        planning = self.planning()
        blocked = blocked_now(self.context.kb, self.context.robot)
        return describe(planning.domain, self.context.robot, blocked)

    def _events(self, request: api.EventQuery) -> api.EventsReply:
        events = self.context.kb.events(
            after=request.after,
            before=request.before,
            kind=request.kind,
            limit=min(request.limit, MAX_EVENTS),
            oldest=request.oldest,
        )
        kept = fitting(events, newest=not request.oldest)
        return api.EventsReply(kept, more=True if len(kept) < len(events) else None)

    def _status(self, request: Empty) -> api.StatusReply:
        kb = self.context.kb
        plan = kb.latest_plan()
        current = self.current()
        diagnoses = self.diagnoses()
        return api.StatusReply(
            robot=self.context.robot.name,
            goals=self._status_goals(),
            plan=plan,
            execution=self._execution(),
            diagnoses=DiagnosisInfo.from_payload(diagnoses) if diagnoses else api.NoDiagnosis(),
            faults=[c for c in kb.components() if c.fault_count or c.permanent_fault],
            tasks=self._section("tasks"),
            components=self._section("components"),
            robots=self._section("robots"),
            planning=current.status() if current is not None else _STARTING,
            goal_counts={s.value: n for s, n in kb.goal_counts().items()},
        )

    def _status_goals(self) -> list[Goal]:
        """The open goals and the newest :data:`~executive.bus.api.planning.RECENT_GOALS`
        others, by id: as many as fit in a reply (the newest open ones first; at most
        :data:`MAX_GOALS` of them are read)."""
        kb = self.context.kb
        open_goals = kb.goals([s for s in GoalState if s.is_open], limit=MAX_GOALS)
        ended = kb.goals([s for s in GoalState if not s.is_open], limit=api.RECENT_GOALS)
        kept = fitting([*ended, *open_goals], newest=True, budget=STATUS_GOALS_BUDGET)
        return sorted(kept, key=lambda g: g.id)  # the open ones first, if not all fit

    def _execution(self) -> ExecutionStatus:
        current = self.current()
        return current.executor.status() if current is not None else ExecutionStatus()

    def _section(self, name: str) -> Any:
        """A section another service adds to ``status``; its error if it did not answer."""
        section = self.extra_status.get(name)
        if section is None:
            return None
        try:
            return section()
        except DuraError as e:
            return api.Unanswered(str(e))


_STARTING = PlannerStatus(starting=True)  # the planner is warming up


def _names_goal(event: Event, goal_id: int) -> bool:
    goals = event.data.get("goals") if isinstance(event.data, dict) else None
    return isinstance(goals, list) and goal_id in goals


def fitting(records: list[R], *, newest: bool, budget: int = EVENTS_BUDGET) -> list[R]:
    """As many of ``records`` (events, goals) as one reply carries (``budget`` bytes):
    the newest of them, or the oldest (none if the first alone is larger)."""
    kept: list[R] = []
    size = 0
    for found in reversed(records) if newest else records:
        size += len(encode(plain(found))) + 1
        if size > budget:
            break
        kept.append(found)
    return kept[::-1] if newest else kept
