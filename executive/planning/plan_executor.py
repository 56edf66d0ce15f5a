"""The plan executor (thesis 5.1.2): run a partial-order plan, event by event.

A step is dispatched as soon as the steps it comes after have reached their
timepoints and its at-start condition holds in the knowledge base's facts; nothing
polls. A :class:`~executive.planning.task_runner.TaskRunner` carries the step out (the
task executor; in unit tests a scripted runner) and reports back through a
:class:`~executive.planning.task_runner.StepReport`. When a step starts its at-start
effects are applied to the KB facts, while it runs its over-all condition is checked
whenever facts change, and when it ends its at-end condition is checked and its at-end
effects applied. A step running past its duration by more than the margin times out.
Actions without a task complete at once with their effects (the rules for steps:
:mod:`executive.planning.plan_run`).

A failed, timed-out or violated step stops dispatching and asks for replanning; its
at-start effects are taken back (the world is as it was before the step, as far as the
executive knows); the steps still running go on until the goal planner has a new plan.
The goal planner pauses the executor before it plans: interruptible tasks pause, the
others finish first (thesis Figures 5.7, 5.8). A new plan adopts a paused or running
step that is one of its first steps (same action and objects); the others are cancelled
and their at-start effects undone, as the planner assumed when it planned.

Every step is an event in the KB log: PLAN_START, DISPATCH, START, ADOPT (a new plan
continues it), END, FAIL, CANCEL, REPLAN. A step's events name its plan and index and
its run (the id of its DISPATCH event, kept by the plan that adopts it); each change a
step makes to the facts is one transaction with its event, and the old plan's steps
end as its own before the new plan takes over: crash recovery relies on both
(:mod:`executive.planning.recovery`). Each stored plan step keeps what happened to it. Goal and plan states are not the executor's to write: it reports each change
(a plan executing, succeeded or failed; a goal executing, achieved, or past its
deadline) to their owner, the goal planner, which applies them on its own thread
(:meth:`PlanExecutor.report_to`, :mod:`executive.planning.state_change`); an executor
without an owner (on its own, as in its unit tests) writes them itself.

All work happens on one thread that takes jobs from a queue, so the state needs no
locks; the public methods post to the queue (and some wait for the answer).
:meth:`PlanExecutor.status` never waits: it answers from a snapshot taken after each job.
"""

from __future__ import annotations

import functools
import itertools
import threading
from collections.abc import Callable, Collection, Sequence
from dataclasses import dataclass
from typing import Any, TypeVar

from executive.bus.clock import Clock, system_clock
from executive.bus.reports import ExecutionStatus, GoalProgress, StepStatus
from executive.bus.timers import Timer
from executive.bus.worker import Worker
from executive.planning.expression import WorldState, atoms
from executive.planning.goals import GoalSpec
from executive.planning.look_ahead import look_ahead, steps_ahead
from executive.planning.partial_order import PartialOrderPlan
from executive.planning.plan_run import PlanRun, RunContext
from executive.planning.recovery import recover
from executive.planning.state_change import Change, GoalChange, PlanChange, apply_change
from executive.planning.step_run import (
    ExecutionLimits,
    Key,
    StepRun,
    StepState,
    cancel_timer,
    start_timer,
)
from executive.planning.task_runner import Progress, StepReport, StepTask, TaskRunner
from knowledge.knowledge_base import KnowledgeBase
from knowledge.records import Fact, GoalState, PlanState

# the runner port and crash recovery moved to modules of their own; callers keep
# importing them from here
__all__ = [
    "ExecutionLimits",
    "ExecutionStatus",
    "PlanExecutor",
    "StepReport",
    "StepState",
    "StepTask",
    "TaskRunner",
    "recover",
]

T = TypeVar("T")


@dataclass
class _Goal:
    spec: GoalSpec
    mentions: frozenset[Key]
    done: bool = False
    in_time: bool = False
    timer: Timer | None = None


class PlanExecutor:
    """Runs one plan at a time (see the module docstring).

    Args:
        kb: the knowledge base whose facts conditions are checked against.
        runner: carries out steps whose action has a task.
        tasks: the actions that have a task; the others complete at once.
        on_replan: called (on the executor's thread) with the reason when a new plan
            is needed; the goal planner wakes up on it.
        clock: robot time (step timeouts and goal deadlines are robot seconds).
        watch_ahead: check the rest of the plan when facts change outside it
            (:mod:`executive.planning.look_ahead`); off only to measure what it gains.
    """

    def __init__(
        self,
        kb: KnowledgeBase,
        runner: TaskRunner,
        tasks: Collection[str],
        on_replan: Callable[[str], None],
        limits: ExecutionLimits | None = None,
        *,
        clock: Clock | None = None,
        watch_ahead: bool = True,
    ) -> None:
        self.kb = kb
        self.clock = clock or system_clock()
        self.watch_ahead = watch_ahead
        self.runner = runner
        self.tasks = frozenset(tasks)
        self.on_replan = on_replan
        self.limits = limits or ExecutionLimits()
        self._worker = Worker("plan executor", after_each=self._after_each)
        self._tell: Callable[[Change], object] = functools.partial(apply_change, kb)
        self._context = RunContext(
            kb,
            runner,
            self.tasks,
            self.limits,
            post=self._worker.post,
            report=lambda report, progress, value: self._worker.post(
                lambda: self._report(report, progress, value)
            ),
            tell=lambda change: self._tell(change),  # noqa: PLW0108 (report_to replaces _tell)
            on_replan=on_replan,
            tokens=itertools.count(1),
            clock=self.clock,
        )
        self._run: PlanRun | None = None
        self._goals: list[_Goal] = []
        self._paused = False
        self._idle = threading.Event()  # set while paused with nothing critical running
        self._snapshot = ExecutionStatus()
        self._upcoming: tuple[int | None, tuple[int, ...]] = (None, ())  # told the runner

    # --- lifecycle ----------------------------------------------------------------------

    def report_to(self, owner: Callable[[Change], object]) -> None:
        """Report goal and plan state changes to ``owner`` instead of writing them.

        ``owner`` is called on the executor's thread and must not wait for anything
        (the goal planner posts the change to its own thread).
        """

        def adopt() -> None:
            self._tell = owner

        self._worker.post(adopt)

    def start(self) -> None:
        self._worker.start()

    def stop(self) -> None:
        """Cancel every running task and stop the thread; idempotent."""
        if self._worker.running:
            self._call(self._cancel_all)
            self._worker.stop()

    def _after_each(self) -> None:
        """Take the snapshot :meth:`status` answers from; tell :meth:`pause` when idle."""
        run = self._run
        self._snapshot = ExecutionStatus(
            plan=None if run is None else run.plan_id,
            paused=self._paused,
            failed=run is not None and run.failed,
            steps=()
            if run is None
            else tuple(
                StepStatus(r.step.index, r.step.label, r.state.value) for r in run.runs.values()
            ),
            goals=tuple(GoalProgress(g.spec.id, g.done) for g in self._goals),
        )
        if self._paused and not (run is not None and run.critical()):
            self._idle.set()
        self._tell_upcoming(run)

    def _tell_upcoming(self, run: PlanRun | None) -> None:
        """Tell the runner which steps are still to come, when that changed."""
        steps = [] if run is None or run.finished else [
            r.step for r in run.runs.values() if r.state is StepState.PENDING
        ]  # fmt: skip
        upcoming = (None if run is None else run.plan_id, tuple(s.index for s in steps))
        if upcoming != self._upcoming:
            self._upcoming = upcoming
            self.runner.upcoming(upcoming[0], steps)

    def _call(self, fn: Callable[[], T], timeout: float | None = None) -> T:
        """Run ``fn`` on the executor's thread and return its result, with the snapshot
        already up to date."""

        def job() -> T:
            try:
                return fn()
            finally:
                self._after_each()

        return self._worker.call(job, timeout)

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

    def abandon(self, reason: str = "no plan") -> None:
        """Drop the current plan (no plan for any goal, or no goal for the plan): cancel
        its tasks, undo the at-start effects of those under way, and end the pause."""
        self._call(lambda: self._abandon(reason))

    def facts_changed(self, changed: Collection[Key] = ()) -> None:
        """Facts changed outside the executor: check the running steps' conditions, and
        the rest of the plan for a ``changed`` fact (:mod:`.look_ahead`)."""

        def react() -> None:
            self._react()
            self._look_ahead(frozenset(changed))

        self._worker.post(react)

    def planning_facts(self) -> list[Fact]:
        """The KB facts with the at-start effects of paused steps undone: the state the
        planner plans from (a new plan either adopts such a step or it is undone)."""
        return self._call(self._planning_facts)

    def status(self) -> ExecutionStatus:
        """The current plan and the state of each step (for ``dura status``), as of the
        last job: it never waits for the executor's thread."""
        return self._snapshot

    # --- work on the executor's thread --------------------------------------------------

    def _execute(self, plan: PartialOrderPlan, plan_id: int, goals: Sequence[GoalSpec]) -> None:
        old = self._run
        for g in self._goals:
            cancel_timer(g.timer)
        run = PlanRun(plan, plan_id, self._context)
        pairs: list[tuple[StepRun, StepRun]] = []
        if old is not None:
            # the old plan's steps end as its own (their events name the old plan),
            # before the new plan takes over the ones it continues
            pairs, left = run.continuing([r for r in old.runs.values() if r.state.active])
            for step in left:
                old.cancel(step, "not in the new plan", undo=True)
        self._run = run
        self._tell(PlanChange(plan_id, PlanState.EXECUTING))
        self._goals = []
        for spec in goals:
            goal = _Goal(spec, atoms(spec.expression))
            if spec.deadline is not None:
                goal.timer = start_timer(
                    self.clock.wall(spec.deadline),
                    self._worker.post,
                    functools.partial(self._deadline, goal),
                )
            self._goals.append(goal)
            self._tell(GoalChange(spec.id, GoalState.EXECUTING))
        run.event("PLAN_START", steps=len(plan.steps), goals=[g.id for g in goals])
        run.adopt(pairs, None if old is None else old.plan_id)
        self._paused = False
        self._resume_steps()
        self._react()

    def _pause(self) -> None:
        self._paused = True
        if self._run is not None:
            self._run.pause()

    def _resume(self) -> None:
        self._paused = False
        self._resume_steps()
        self._react()

    def _resume_steps(self) -> None:
        """Resume the paused steps, handling what each reported while paused."""
        run = self._run
        if run is None:
            return
        for step in run.runs.values():
            if step.state is StepState.PAUSED:
                held = run.unpause(step)
                if held is not None:
                    self._handle(step, *held)

    def _planning_facts(self) -> list[Fact]:
        values = {(f.name, f.args): f.value for f in self.kb.facts()}
        if self._run is not None:
            self._run.undone(values)
        return [Fact(name, args, v) for (name, args), v in sorted(values.items())]

    def _abandon(self, reason: str) -> None:
        if self._run is not None:
            self._run.cancel_active(reason)
        for g in self._goals:
            cancel_timer(g.timer)
        self._run, self._goals = None, []
        self._paused = False

    def _cancel_all(self) -> None:
        if self._run is not None:
            self._run.cancel_active("the executor stops")
        for g in self._goals:
            cancel_timer(g.timer)

    def _report(self, report: StepReport, progress: Progress, value: Any) -> None:
        plan_id, index, token = report.route
        run = self._run
        step = None if run is None else run.runs.get(index)
        if run is None or step is None or plan_id != run.plan_id or step.token != token:
            return  # a report from a step that was cancelled or replaced
        if token < 0:
            return
        if step.state is StepState.PAUSED and progress is not Progress.STARTED:
            step.held = (progress, value)  # the planner plans from the paused state
            return
        self._handle(step, progress, value)

    def _handle(self, step: StepRun, progress: Progress, value: Any) -> None:
        if self._run is not None:
            self._run.handle(step, progress, value)
        self._react()

    def _react(self) -> None:
        """Bring everything up to date with the facts: conditions, dispatching, goals."""
        run = self._run
        if run is None or run.finished:
            return
        state = run.state()
        for step in list(run.runs.values()):
            if step.state is StepState.RUNNING and not state.holds(step.step.over_all):
                run.fail(step, f"over-all condition {step.step.over_all} no longer holds")
                state = run.state()
        self._check_goals(state)
        if run.failed:
            return
        progress = not self._paused
        while progress:
            progress = False
            for step in run.runs.values():
                ready = step.state is StepState.PENDING and run.ready(step)
                if ready and state.holds(step.step.at_start):
                    run.dispatch(step)
                    state = run.state()
                    progress = True
            self._check_goals(state)
        if run.failed:
            return
        if all(r.state is StepState.ENDED for r in run.runs.values()):
            self._finish(run)
        elif not self._paused and not any(r.state.active for r in run.runs.values()):
            waiting = [r for r in run.runs.values() if r.state is StepState.PENDING]
            blocked = next((r for r in waiting if run.ready(r)), waiting[0])
            run.fail_plan(
                f"step {blocked.step.label} cannot start: {blocked.step.at_start} does not hold"
            )

    def _look_ahead(self, changed: frozenset[Key]) -> None:
        run = self._run
        if run is None or run.failed or run.finished or not self.watch_ahead:
            return
        goals = [g.spec.expression for g in self._goals if not g.done]
        blocked = look_ahead(steps_ahead(run.runs.values()), self.kb.facts(), changed, goals)
        if blocked is not None:
            run.fail_plan(str(blocked))

    def _finish(self, run: PlanRun) -> None:
        open_goals = [g for g in self._goals if not g.done]
        if run.plan_id is not None:
            self._tell(PlanChange(run.plan_id, PlanState.SUCCEEDED))
        run.finished = True
        if open_goals:
            missing = ", ".join(str(g.spec.expression) for g in open_goals)
            run.failed = True
            run.event("REPLAN", reason=f"the plan ended but {missing} does not hold")
            self.on_replan(f"the plan ended but {missing} does not hold")

    # --- goals ---------------------------------------------------------------------------

    def _check_goals(self, state: WorldState) -> None:
        """A goal is achieved when it holds and no unfinished step may change what it
        mentions; a goal with a deadline that holds in time is remembered as in time."""
        pending = [] if self._run is None else self._run.unfinished()
        for goal in self._goals:
            if goal.done or not state.holds(goal.spec.expression):
                continue
            goal.in_time = True
            if any(r.touches(goal.mentions) for r in pending):
                continue
            goal.done = True
            cancel_timer(goal.timer)
            self._tell(GoalChange(goal.spec.id, GoalState.ACHIEVED))

    def _deadline(self, goal: _Goal) -> None:
        if goal.done or goal.in_time or goal not in self._goals:
            return
        self._check_goals(WorldState(self.kb.facts()))
        if goal.done or goal.in_time:
            return
        goal.done = True
        reason = f"missed its deadline ({goal.spec.deadline:g} s after planning)"
        self._tell(GoalChange(goal.spec.id, GoalState.FAILED, reason))
        if self._run is not None:
            self._run.fail_plan(f"goal {goal.spec.id} {reason}")
