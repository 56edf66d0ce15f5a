"""The plan executer (thesis 5.1.2): run a partial-order plan, event by event.

A step is dispatched as soon as the steps it comes after have reached their
timepoints and its at-start condition holds in the knowledge base's facts; nothing
polls. A :class:`TaskRunner` carries the step out (the task executor; in unit tests a
scripted runner) and reports back through a :class:`StepReport`. When a step starts
its at-start effects are applied to the KB facts, while it runs its over-all condition
is checked whenever facts change, and when it ends its at-end condition is checked and
its at-end effects applied. A step running past its duration by more than the margin
times out. Actions without a task complete at once with their effects.

A failed, timed-out or violated step stops dispatching and asks for replanning; its
at-start effects are taken back (the world is as it was before the step, as far as the
executive knows); the steps still running go on until the goal planner has a new plan. The goal planner
pauses the executer before it plans: interruptible tasks pause, the others finish
first (thesis Figures 5.7, 5.8). A new plan adopts a paused or running step that is
one of its first steps (same action and objects); the others are cancelled and their
at-start effects undone, as the planner assumed when it planned.

Every step is an event in the KB log: PLAN_START, DISPATCH, START, END, FAIL, CANCEL,
REPLAN, and GOAL_ACHIEVED / GOAL_FAILED from the goals' state changes.

All work happens on one thread that takes events from a queue, so the state needs
no locks; the public methods post to the queue (and some wait for the answer).
"""

from __future__ import annotations

import enum
import functools
import logging
import threading
import time
from abc import ABC, abstractmethod
from collections.abc import Callable, Collection, Sequence
from dataclasses import dataclass, field
from typing import Any, TypeVar

from executive.bus.worker import Worker
from executive.planning.expression import WorldState, atoms
from executive.planning.goals import GoalSpec
from executive.planning.partial_order import Effect, PartialOrderPlan, Step, Timepoint, apply
from knowledge.knowledge_base import KnowledgeBase
from knowledge.records import Fact, GoalState, PlanState

log = logging.getLogger("dura.plan_executer")

T = TypeVar("T")


def recover(kb: KnowledgeBase) -> list[str]:
    """After the executive died: take back the at-start effects of the steps it had
    started and not ended (recorded with their START events); returns their labels.

    Call before planning again, when the current run's EXECUTIVE_STARTED is logged.
    """
    runs = [e.id for e in kb.events(kind="EXECUTIVE_STARTED")]
    if len(runs) < 2:
        return []
    unfinished: dict[tuple[Any, Any], Any] = {}
    for e in kb.events(after=runs[-2] - 1):
        if e.id >= runs[-1]:
            break
        key = (e.data.get("plan"), e.data.get("step"))
        if e.kind == "START":
            unfinished[key] = e
        elif e.kind in ("END", "FAIL", "CANCEL"):
            unfinished.pop(key, None)
    labels = []
    for e in unfinished.values():
        undo = e.data.get("undo") or []
        with kb.transaction():
            kb.update_facts(
                add=[Fact(n, tuple(a), v) for n, a, v in undo if v is not None],
                remove=[Fact(n, tuple(a)) for n, a, v in undo if v is None],
            )
            kb.log_event("CANCEL", e.subject, {**e.data, "reason": "the executive died"})
        labels.append(e.subject)
    return labels


# --- the task runner interface -------------------------------------------------------


class StepReport:
    """How a runner reports on one step; call from any thread, late calls are ignored."""

    def __init__(self, post: Callable[[StepReport, str, Any], None]) -> None:
        self._send = post
        self.route: tuple[int | None, int, int] = (None, -1, -1)  # plan, step, token

    def _post(self, kind: str, value: Any) -> None:
        self._send(self, kind, value)

    def started(self) -> None:
        """The step's behavior runs (its configuration is ready)."""
        self._post("started", None)

    def succeeded(self, result: Any = None) -> None:
        self._post("succeeded", result)

    def failed(self, reason: str) -> None:
        self._post("failed", reason)


class StepTask(ABC):
    """A step the runner is carrying out."""

    interruptible: bool = True

    @abstractmethod
    def pause(self) -> None:
        """Pause at the next interruption point (only called when interruptible)."""

    @abstractmethod
    def resume(self) -> None: ...

    @abstractmethod
    def cancel(self) -> None:
        """Stop for good; no report is expected afterwards."""


class TaskRunner(ABC):
    """Carries out plan steps: the task executor, or a scripted runner in unit tests."""

    @abstractmethod
    def run(self, step: Step, plan_id: int, report: StepReport) -> StepTask:
        """Start carrying out a step and return at once; report through ``report``."""


# --- state ---------------------------------------------------------------------------


class StepState(enum.Enum):
    PENDING = "pending"
    DISPATCHED = "dispatched"  # asked of the runner, not started yet
    RUNNING = "running"
    PAUSED = "paused"
    ENDED = "ended"
    FAILED = "failed"
    CANCELLED = "cancelled"

    @property
    def active(self) -> bool:
        return self in (StepState.DISPATCHED, StepState.RUNNING, StepState.PAUSED)


@dataclass(frozen=True)
class ExecutionLimits:
    """A step times out ``margin`` seconds (at least ``relative`` of its duration)
    after its expected duration."""

    margin: float = 5.0
    relative: float = 0.5

    def timeout(self, duration: float) -> float:
        return duration + max(self.margin, self.relative * duration)


@dataclass
class _Run:
    """What the executer knows about one step of the current plan."""

    step: Step
    state: StepState = StepState.PENDING
    task: StepTask | None = None
    report: StepReport | None = None
    started: bool = False  # at-start effects applied
    was: StepState = StepState.PENDING  # the state before a pause
    undo: dict[tuple[str, tuple[str, ...]], bool | float | None] = field(default_factory=dict)
    elapsed: float = 0.0  # seconds run before the current stretch
    since: float = 0.0  # monotonic time the current stretch began
    timer: threading.Timer | None = None
    token: int = 0
    held: tuple[str, Any] | None = None  # an end reported while paused, handled on resume


@dataclass
class _Goal:
    spec: GoalSpec
    mentions: frozenset[tuple[str, tuple[str, ...]]]
    done: bool = False
    in_time: bool = False
    timer: threading.Timer | None = None


class PlanExecuter:
    """Runs one plan at a time (see the module docstring).

    Args:
        kb: the knowledge base whose facts conditions are checked against.
        runner: carries out steps whose action has a task.
        tasks: the actions that have a task; the others complete at once.
        on_replan: called (on the executer's thread) with the reason when a new plan
            is needed; the goal planner wakes up on it.
    """

    def __init__(
        self,
        kb: KnowledgeBase,
        runner: TaskRunner,
        tasks: Collection[str],
        on_replan: Callable[[str], None],
        limits: ExecutionLimits | None = None,
    ) -> None:
        self.kb = kb
        self.runner = runner
        self.tasks = frozenset(tasks)
        self.on_replan = on_replan
        self.limits = limits or ExecutionLimits()
        self._worker = Worker("plan executer", after_each=self._after_each)
        self._plan: PartialOrderPlan | None = None
        self._plan_id: int | None = None
        self._runs: dict[int, _Run] = {}
        self._goals: list[_Goal] = []
        self._paused = False
        self._failed = False
        self._tokens = 0
        self._idle = threading.Event()  # set while paused with nothing critical running

    # --- lifecycle ----------------------------------------------------------------------

    def start(self) -> None:
        self._worker.start()

    def stop(self) -> None:
        """Cancel every running task and stop the thread; idempotent."""
        if self._worker.running:
            self._call(self._cancel_all)
            self._worker.stop()

    def _after_each(self) -> None:
        if self._paused and not self._critical():
            self._idle.set()

    def _call(self, fn: Callable[[], T], timeout: float | None = None) -> T:
        """Run ``fn`` on the executer's thread and return its result."""
        return self._worker.call(fn, timeout)

    # --- commands -----------------------------------------------------------------------

    def execute(self, plan: PartialOrderPlan, plan_id: int, goals: Sequence[GoalSpec]) -> None:
        """Run a new plan (stored in the KB as ``plan_id``) for goals; ends the pause."""
        self._call(lambda: self._execute(plan, plan_id, goals))

    def pause(self, timeout: float | None = None) -> bool:
        """Pause interruptible tasks, let the others finish; True once nothing runs."""
        self._idle.clear()
        self._call(self._pause)
        return self._idle.wait(timeout)

    def resume(self) -> None:
        """Continue the current plan after a pause that brought no new plan."""
        self._call(self._resume)

    def abandon(self) -> None:
        """Drop the current plan (no plan for any goal): cancel its tasks, undo the
        at-start effects of those under way, and end the pause."""
        self._call(self._abandon)

    def facts_changed(self) -> None:
        """Facts changed outside the executer (``dura state set``): check conditions."""
        self._worker.post(self._react)

    def planning_facts(self) -> list[Fact]:
        """The KB facts with the at-start effects of paused steps undone: the state the
        planner plans from (a new plan either adopts such a step or it is undone)."""
        return self._call(self._planning_facts)

    def status(self) -> dict[str, Any]:
        """The current plan and the state of each step (for ``dura status``)."""
        return self._call(self._status)

    # --- work on the executer's thread --------------------------------------------------

    def _status(self) -> dict[str, Any]:
        return {
            "plan": self._plan_id,
            "paused": self._paused,
            "failed": self._failed,
            "steps": [
                {"index": r.step.index, "step": r.step.label, "state": r.state.value}
                for r in self._runs.values()
            ],
            "goals": [{"id": g.spec.id, "achieved": g.done} for g in self._goals],
        }

    def _event(self, kind: str, run: _Run | None = None, **data: Any) -> None:
        if run is not None:
            data = {"plan": self._plan_id, "step": run.step.index, "action": run.step.action,
                    "args": list(run.step.args), **data}  # fmt: skip
            self.kb.log_event(kind, run.step.label, data)
        else:
            self.kb.log_event(kind, f"plan {self._plan_id}", data)

    def _state(self) -> WorldState:
        return WorldState(self.kb.facts())

    def _execute(self, plan: PartialOrderPlan, plan_id: int, goals: Sequence[GoalSpec]) -> None:
        old = [r for r in self._runs.values() if r.state.active]
        for g in self._goals:
            _cancel_timer(g.timer)
        self._plan, self._plan_id, self._failed = plan, plan_id, False
        self._runs = {s.index: _Run(s) for s in plan.steps}
        for run in self._runs.values():
            if run.step.after:
                continue
            match = next(
                (
                    o
                    for o in old
                    if (o.step.action, o.step.args) == (run.step.action, run.step.args)
                ),
                None,
            )
            if match is not None:
                old.remove(match)
                self._adopt(run, match)
        for o in old:
            self._cancel(o, "not in the new plan", undo=True)
        self.kb.set_plan_state(plan_id, PlanState.EXECUTING)
        self._goals = []
        for spec in goals:
            goal = _Goal(spec, atoms(spec.expression))
            if spec.deadline is not None:
                goal.timer = self._timer(spec.deadline, functools.partial(self._deadline, goal))
            self._goals.append(goal)
            self.kb.set_goal_state(spec.id, GoalState.EXECUTING)
        self._event("PLAN_START", steps=len(plan.steps), goals=[g.id for g in goals])
        self._paused = False
        for run in self._runs.values():
            if run.state is StepState.PAUSED:
                self._unpause(run)
        self._react()

    def _adopt(self, run: _Run, old: _Run) -> None:
        """Let a new plan's step continue a task that is already under way."""
        run.state, run.task, run.report = old.state, old.task, old.report
        run.started, run.undo, run.was = old.started, old.undo, old.was
        run.elapsed, run.since, run.held = old.elapsed, old.since, old.held
        _cancel_timer(old.timer)
        run.token = self._next_token()
        if run.report is not None:  # the task's further reports go to the new plan's step
            run.report.route = (self._plan_id, run.step.index, run.token)
        if run.state is StepState.RUNNING:
            self._arm(run)

    def _next_token(self) -> int:
        self._tokens += 1
        return self._tokens

    def _pause(self) -> None:
        self._paused = True
        for run in self._runs.values():
            active = run.state in (StepState.RUNNING, StepState.DISPATCHED)
            if active and run.task is not None and run.task.interruptible:
                run.task.pause()
                run.was, run.state = run.state, StepState.PAUSED
                self._disarm(run)

    def _critical(self) -> bool:
        """Whether a step that cannot be paused is still under way."""
        return any(
            r.state in (StepState.RUNNING, StepState.DISPATCHED) for r in self._runs.values()
        )

    def _resume(self) -> None:
        self._paused = False
        for run in self._runs.values():
            if run.state is StepState.PAUSED:
                self._unpause(run)
        self._react()

    def _unpause(self, run: _Run) -> None:
        if run.task is not None:
            run.task.resume()
        run.state = run.was
        if run.state is StepState.RUNNING:
            self._arm(run)
        if run.held is not None:
            kind, value = run.held
            run.held = None
            self._handle(run, kind, value)

    def _planning_facts(self) -> list[Fact]:
        values = {(f.name, f.args): f.value for f in self.kb.facts()}
        for run in self._runs.values():
            if run.state.active and run.started:
                for key, before in run.undo.items():
                    if before is None:
                        values.pop(key, None)
                    else:
                        values[key] = before
        return [Fact(name, args, v) for (name, args), v in sorted(values.items())]

    def _abandon(self) -> None:
        for run in self._runs.values():
            if run.state.active:
                self._cancel(run, "no plan", undo=True)
        for g in self._goals:
            _cancel_timer(g.timer)
        self._plan, self._plan_id, self._runs, self._goals = None, None, {}, []
        self._paused = False

    def _cancel_all(self) -> None:
        for run in self._runs.values():
            if run.state.active:
                self._cancel(run, "the executer stops", undo=True)
        for g in self._goals:
            _cancel_timer(g.timer)

    def _cancel(self, run: _Run, reason: str, *, undo: bool) -> None:
        if run.held is not None and run.held[0] == "succeeded":
            # it ended while paused: its effects are real, whatever the new plan assumed
            run.state = StepState.RUNNING
            self._end(run, run.held[1])
            return
        if run.task is not None:
            run.task.cancel()
        self._disarm(run)
        run.token = -1
        if undo:
            self._undo(run)
        run.state = StepState.CANCELLED
        self._event("CANCEL", run, reason=reason)

    # --- dispatching ---------------------------------------------------------------------

    def _ready(self, run: _Run) -> bool:
        for p in run.step.after:
            other = self._runs[p.step]
            if other.state is StepState.ENDED:
                continue
            if p.at is Timepoint.START and other.started:
                continue
            return False
        return True

    def _react(self) -> None:
        """Bring everything up to date with the facts: conditions, dispatching, goals."""
        if self._plan is None:
            return
        state = self._state()
        for run in list(self._runs.values()):
            if run.state is StepState.RUNNING and not state.holds(run.step.over_all):
                self._fail(run, f"over-all condition {run.step.over_all} no longer holds")
                state = self._state()
        self._check_goals(state)
        if self._failed:
            return
        progress = not self._paused
        while progress:
            progress = False
            for run in self._runs.values():
                ready = run.state is StepState.PENDING and self._ready(run)
                if ready and state.holds(run.step.at_start):
                    self._dispatch(run)
                    state = self._state()
                    progress = True
            self._check_goals(state)
        if self._failed:
            return
        if all(r.state is StepState.ENDED for r in self._runs.values()):
            self._finish()
        elif not self._paused and not any(r.state.active for r in self._runs.values()):
            waiting = [r for r in self._runs.values() if r.state is StepState.PENDING]
            blocked = next((r for r in waiting if self._ready(r)), waiting[0])
            self._plan_failed(
                f"step {blocked.step.label} cannot start: {blocked.step.at_start} does not hold"
            )

    def _dispatch(self, run: _Run) -> None:
        step = run.step
        self._event("DISPATCH", run)
        if step.action not in self.tasks:
            run.state = StepState.DISPATCHED
            self._start(run)
            self._end(run, None)
            return
        run.state = StepState.DISPATCHED
        run.token = self._next_token()
        run.report = StepReport(
            lambda report, kind, value: self._worker.post(lambda: self._report(report, kind, value))
        )
        run.report.route = (self._plan_id, step.index, run.token)
        run.task = self.runner.run(step, self._plan_id or 0, run.report)

    def _report(self, report: StepReport, kind: str, value: Any) -> None:
        plan_id, index, token = report.route
        run = self._runs.get(index)
        if plan_id != self._plan_id or run is None or run.token != token or token < 0:
            return  # a report from a step that was cancelled or replaced
        if run.state is StepState.PAUSED and kind != "started":
            run.held = (kind, value)  # the planner plans from the paused state
            return
        self._handle(run, kind, value)

    def _handle(self, run: _Run, kind: str, value: Any) -> None:
        if kind == "started":
            self._start(run)
        elif kind == "succeeded":
            self._end(run, value)
        else:
            self._fail(run, f"step {run.step.label} failed: {value}")
        self._react()

    def _apply(self, run: _Run, effects: Sequence[Effect], *, remember: bool) -> None:
        state = self._state()
        add, remove = apply(effects, state)
        if remember:
            before = {(f.name, f.args): f.value for f in self.kb.facts()}
            for f in (*add, *remove):
                run.undo.setdefault((f.name, f.args), before.get((f.name, f.args)))
        if add or remove:
            self.kb.update_facts(add=add, remove=remove)

    def _start(self, run: _Run) -> None:
        if run.started:
            return
        if run.state is StepState.PAUSED:
            run.was = StepState.RUNNING
        if not self._state().holds(run.step.at_start):
            self._fail(
                run, f"at-start condition {run.step.at_start} of {run.step.label} no longer holds"
            )
            return
        with self.kb.transaction():  # a crash leaves both or neither: see recover()
            self._apply(run, run.step.start_effects, remember=True)
            undo = [[name, list(args), before] for (name, args), before in run.undo.items()]
            self._event("START", run, undo=undo)
        run.started = True
        if run.state is not StepState.PAUSED:
            run.state = StepState.RUNNING
            self._arm(run)

    def _end(self, run: _Run, result: Any) -> None:
        if not run.started:
            self._start(run)
            if run.state is StepState.FAILED:
                return
        state = self._state()
        for what, condition in (("over-all", run.step.over_all), ("at-end", run.step.at_end)):
            if not state.holds(condition):
                self._fail(
                    run,
                    f"{what} condition {condition} of {run.step.label} does not hold at its end",
                )
                return
        self._disarm(run)
        self._apply(run, run.step.end_effects, remember=False)
        run.state = StepState.ENDED
        self._event("END", run, **({"result": result} if result is not None else {}))

    def _undo(self, run: _Run) -> None:
        """Take back a started step's at-start effects: as far as the executive knows,
        the world is as it was before the step (components that know better write facts)."""
        if run.started and run.undo:
            self.kb.update_facts(
                add=[Fact(n, a, v) for (n, a), v in run.undo.items() if v is not None],
                remove=[Fact(n, a) for (n, a), v in run.undo.items() if v is None],
            )

    def _fail(self, run: _Run, reason: str) -> None:
        if run.task is not None and run.state.active:
            run.task.cancel()
        self._disarm(run)
        run.token = -1
        self._undo(run)
        run.state = StepState.FAILED
        self._event("FAIL", run, reason=reason)
        self._plan_failed(reason)

    def _plan_failed(self, reason: str) -> None:
        if self._failed:
            return
        self._failed = True
        if self._plan_id is not None:
            self.kb.set_plan_state(self._plan_id, PlanState.FAILED, reason)
        self._event("REPLAN", reason=reason)
        self.on_replan(reason)

    def _finish(self) -> None:
        open_goals = [g for g in self._goals if not g.done]
        if self._plan_id is not None:
            self.kb.set_plan_state(self._plan_id, PlanState.SUCCEEDED)
        self._plan = None
        if open_goals:
            missing = ", ".join(str(g.spec.expression) for g in open_goals)
            self._failed = True
            self._event("REPLAN", reason=f"the plan ended but {missing} does not hold")
            self.on_replan(f"the plan ended but {missing} does not hold")

    # --- goals ---------------------------------------------------------------------------

    def _check_goals(self, state: WorldState) -> None:
        """A goal is achieved when it holds and no unfinished step may change what it
        mentions; a goal with a deadline that holds in time is remembered as in time."""
        pending = [r for r in self._runs.values() if r.state is StepState.PENDING or r.state.active]
        for goal in self._goals:
            if goal.done or not state.holds(goal.spec.expression):
                continue
            goal.in_time = True
            if any(self._touches(r, goal.mentions) for r in pending):
                continue
            goal.done = True
            _cancel_timer(goal.timer)
            self.kb.set_goal_state(goal.spec.id, GoalState.ACHIEVED)

    @staticmethod
    def _touches(run: _Run, mentions: frozenset[tuple[str, tuple[str, ...]]]) -> bool:
        effects = (
            run.step.end_effects
            if run.started
            else (*run.step.start_effects, *run.step.end_effects)
        )
        return any((e.name, e.args) in mentions for e in effects)

    def _deadline(self, goal: _Goal) -> None:
        if goal.done or goal.in_time or goal not in self._goals:
            return
        self._check_goals(self._state())
        if goal.done or goal.in_time:
            return
        goal.done = True
        reason = f"missed its deadline ({goal.spec.deadline:g} s after planning)"
        self.kb.set_goal_state(goal.spec.id, GoalState.FAILED, reason)
        self._plan_failed(f"goal {goal.spec.id} {reason}")

    # --- timeouts -------------------------------------------------------------------------

    def _timer(self, seconds: float, fn: Callable[[], None]) -> threading.Timer:
        timer = threading.Timer(max(0.0, seconds), lambda: self._worker.post(fn))
        timer.daemon = True
        timer.start()
        return timer

    def _arm(self, run: _Run) -> None:
        """Start the timeout of a running step (for what is left of it)."""
        _cancel_timer(run.timer)
        run.since = time.monotonic()
        if run.step.duration is None:
            return
        limit = self.limits.timeout(run.step.duration)
        token = run.token
        run.timer = self._timer(limit - run.elapsed, lambda: self._timed_out(run, token, limit))

    def _disarm(self, run: _Run) -> None:
        if run.timer is not None:
            _cancel_timer(run.timer)
            run.timer = None
            run.elapsed += time.monotonic() - run.since

    def _timed_out(self, run: _Run, token: int, limit: float) -> None:
        if run.token != token or run.state is not StepState.RUNNING:
            return
        self._fail(
            run,
            f"step {run.step.label} timed out: still running after {limit:g} s "
            f"(expected {run.step.duration:g} s)",
        )


def _cancel_timer(timer: threading.Timer | None) -> None:
    if timer is not None:
        timer.cancel()
