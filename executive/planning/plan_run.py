"""One plan under way: which of its steps may start, what starting and ending one does
to the facts, when one times out, and how the plan fails.

The plan executor (:mod:`executive.planning.plan_executor`) keeps one :class:`PlanRun`
for the plan it executes and drives it from its thread; this module holds the rules for
steps, the executor the commands, the pause, the goals and the thread.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Iterable, Iterator, Sequence
from dataclasses import dataclass, field
from typing import Any

from executive.bus.clock import Clock
from executive.planning.expression import WorldState
from executive.planning.partial_order import Effect, PartialOrderPlan, Timepoint, apply
from executive.planning.state_change import Change, PlanChange
from executive.planning.step_run import (
    ExecutionLimits,
    Key,
    StepRun,
    StepState,
    cancel_timer,
    start_timer,
)
from executive.planning.task_runner import Progress, StepReport, TaskRunner
from knowledge.knowledge_base import KnowledgeBase
from knowledge.records import Fact, PlanState


@dataclass(frozen=True)
class RunContext:
    """What every plan run of one executor shares.

    Args:
        post: run a function on the executor's thread, later.
        report: where a runner's reports go (posts them to the executor's thread).
        tell: report a plan state change to its owner.
        on_replan: ask for a new plan, with the reason.
        tokens: numbers that tell a step's current task from earlier ones.
        clock: robot time: durations and timeouts are robot seconds.
    """

    kb: KnowledgeBase
    runner: TaskRunner
    tasks: frozenset[str]
    limits: ExecutionLimits
    post: Callable[[Callable[[], None]], None]
    report: Callable[[StepReport, Progress, Any], None]
    tell: Callable[[Change], object]
    on_replan: Callable[[str], None]
    tokens: Iterator[int]
    clock: Clock = field(default_factory=Clock)


class PlanRun:
    """The steps of one plan as they run (see the module docstring)."""

    def __init__(self, plan: PartialOrderPlan, plan_id: int | None, context: RunContext) -> None:
        self.plan = plan
        self.plan_id = plan_id
        self.runs = {s.index: StepRun(s) for s in plan.steps}
        self.failed = False  # asked for a new plan
        self.finished = False  # every step ended
        self._c = context

    # --- what the plan looks like -----------------------------------------------------

    def event(self, kind: str, run: StepRun | None = None, *, state: str = "", **data: Any) -> int:
        """Log an event of the plan, or of one of its steps (with its run, and ``state``
        as the stored step's new state, in the same transaction); returns its id."""
        kb = self._c.kb
        if run is None:
            return kb.log_event(kind, f"plan {self.plan_id}", data)
        performer = self._c.runner.performer(run.step.action, run.step.args)
        data = {"plan": self.plan_id, "step": run.step.index, "action": run.step.action,
                "args": list(run.step.args), **({} if run.id is None else {"run": run.id}),
                **({} if performer is None else {"robot": performer}), **data}  # fmt: skip
        with kb.transaction():
            if state and self.plan_id is not None:
                kb.set_step_state(self.plan_id, run.step.index, state)
            return kb.log_event(kind, run.step.label, data)

    def state(self) -> WorldState:
        return WorldState(self._c.kb.facts())

    def ready(self, run: StepRun) -> bool:
        """Whether every step it comes after has reached its timepoint."""
        for p in run.step.after:
            other = self.runs[p.step]
            if other.state is StepState.ENDED:
                continue
            if p.at is Timepoint.START and other.started:
                continue
            return False
        return True

    def critical(self) -> bool:
        """Whether a step that cannot be paused is still under way."""
        return any(r.state in (StepState.RUNNING, StepState.DISPATCHED) for r in self.runs.values())

    def unfinished(self) -> list[StepRun]:
        return [r for r in self.runs.values() if r.state is StepState.PENDING or r.state.active]

    def undone(self, values: dict[Key, bool | float]) -> None:
        """Take the at-start effects of the steps under way out of ``values``."""
        for run in self.runs.values():
            if run.state.active and run.started:
                for key, before in run.undo.items():
                    if before is None:
                        values.pop(key, None)
                    else:
                        values[key] = before

    # --- a new plan, pauses ----------------------------------------------------------

    def continuing(
        self, old: Sequence[StepRun]
    ) -> tuple[list[tuple[StepRun, StepRun]], list[StepRun]]:
        """Which first steps continue which of an earlier plan's steps under way (same
        action and objects), and the earlier steps no first step continues."""
        left = list(old)
        pairs = []
        for run in self.runs.values():
            if run.step.after:
                continue
            match = next(
                (
                    o
                    for o in left
                    if (o.step.action, o.step.args) == (run.step.action, run.step.args)
                ),
                None,
            )
            if match is not None:
                left.remove(match)
                pairs.append((run, match))
        return pairs, left

    def adopt(self, pairs: Sequence[tuple[StepRun, StepRun]], old_plan: int | None) -> None:
        """Let first steps continue the runs of an earlier plan's steps (see
        :meth:`continuing`): the run keeps its identity, its task reports to this plan."""
        kb = self._c.kb
        for run, old in pairs:
            run.take_over(old)
            run.token = next(self._c.tokens)
            if run.report is not None:  # the task's further reports go to this plan's step
                run.report.route = (self.plan_id, run.step.index, run.token)
            with kb.transaction():
                if old_plan is not None:
                    kb.set_step_state(old_plan, old.step.index, "adopted")
                self.event(
                    "ADOPT", run, state="running" if run.started else "dispatched",
                    from_plan=old_plan, from_step=old.step.index,
                )  # fmt: skip
            if run.state is StepState.RUNNING:
                self.arm(run)

    def pause(self) -> None:
        """Pause the interruptible tasks under way; the others go on."""
        for run in self.runs.values():
            active = run.state in (StepState.RUNNING, StepState.DISPATCHED)
            if active and run.task is not None and run.task.interruptible:
                run.task.pause()
                run.was, run.state = run.state, StepState.PAUSED
                run.stop_clock()

    def unpause(self, run: StepRun) -> tuple[Progress, Any] | None:
        """Resume a paused step; returns what it reported while paused, if anything."""
        if run.task is not None:
            run.task.resume()
        run.state = run.was
        if run.state is StepState.RUNNING:
            self.arm(run)
        held, run.held = run.held, None
        return held

    def cancel_active(self, reason: str) -> None:
        for run in self.runs.values():
            if run.state.active:
                self.cancel(run, reason, undo=True)

    def cancel(self, run: StepRun, reason: str, *, undo: bool) -> None:
        if run.held is not None and run.held[0] is Progress.SUCCEEDED:
            # it ended while paused: its effects are real, whatever the new plan assumed
            run.state = StepState.RUNNING
            self.end(run, run.held[1])
            return
        if run.task is not None:
            run.task.cancel()
        run.stop_clock()
        run.token = -1
        with self._c.kb.transaction():  # a crash leaves both or neither: see recovery.py
            if undo:
                self.undo(run)
            self.event("CANCEL", run, state="cancelled", reason=reason)
        run.state = StepState.CANCELLED

    # --- a step's life ----------------------------------------------------------------

    def dispatch(self, run: StepRun) -> None:
        step = run.step
        run.id = self.event("DISPATCH", run, state="dispatched")  # the run's identity
        if step.action not in self._c.tasks:
            run.state = StepState.DISPATCHED
            self.start(run)
            self.end(run, None)
            return
        run.state = StepState.DISPATCHED
        run.token = next(self._c.tokens)
        run.report = StepReport(self._c.report)
        run.report.route = (self.plan_id, step.index, run.token)
        run.task = self._c.runner.run(step, self.plan_id or 0, run.report)

    def handle(self, run: StepRun, progress: Progress, value: Any) -> None:
        """What the runner reported about a step."""
        if progress is Progress.STARTED:
            self.start(run)
        elif progress is Progress.SUCCEEDED:
            self.end(run, value)
        else:
            self.fail(run, f"step {run.step.label} failed: {value}")

    def apply(self, run: StepRun, effects: Iterable[Effect], *, remember: bool) -> None:
        kb = self._c.kb
        add, remove = apply(effects, self.state())
        if remember:
            before = {(f.name, f.args): f.value for f in kb.facts()}
            for f in (*add, *remove):
                run.undo.setdefault((f.name, f.args), before.get((f.name, f.args)))
        if add or remove:
            kb.update_facts(add=add, remove=remove)

    def start(self, run: StepRun) -> None:
        if run.started:
            return
        if run.state is StepState.PAUSED:
            run.was = StepState.RUNNING
        if not self.state().holds(run.step.at_start):
            self.fail(
                run, f"at-start condition {run.step.at_start} of {run.step.label} no longer holds"
            )
            return
        with self._c.kb.transaction():  # a crash leaves both or neither: see recovery.py
            self.apply(run, run.step.start_effects, remember=True)
            undo = [[name, list(args), before] for (name, args), before in run.undo.items()]
            self.event("START", run, state="running", undo=undo)
        run.started = True
        if run.state is not StepState.PAUSED:
            run.state = StepState.RUNNING
            self.arm(run)

    def end(self, run: StepRun, result: Any) -> None:
        if not run.started:
            self.start(run)
            if run.state is StepState.FAILED:
                return
        state = self.state()
        for what, condition in (("over-all", run.step.over_all), ("at-end", run.step.at_end)):
            if not state.holds(condition):
                self.fail(
                    run,
                    f"{what} condition {condition} of {run.step.label} does not hold at its end",
                )
                return
        run.stop_clock()
        with self._c.kb.transaction():  # a crash leaves both or neither: see recovery.py
            self.apply(run, run.step.end_effects, remember=False)
            outcome = {"result": result} if result is not None else {}
            self.event("END", run, state="ended", **outcome)
        run.state = StepState.ENDED

    def undo(self, run: StepRun) -> None:
        """Take back a started step's at-start effects: as far as the executive knows,
        the world is as it was before the step (components that know better write facts)."""
        if run.started and run.undo:
            self._c.kb.update_facts(
                add=[Fact(n, a, v) for (n, a), v in run.undo.items() if v is not None],
                remove=[Fact(n, a) for (n, a), v in run.undo.items() if v is None],
            )

    def fail(self, run: StepRun, reason: str) -> None:
        if run.task is not None and run.state.active:
            run.task.cancel()
        run.stop_clock()
        run.token = -1
        with self._c.kb.transaction():  # a crash leaves both or neither: see recovery.py
            self.undo(run)
            self.event("FAIL", run, state="failed", reason=reason)
        run.state = StepState.FAILED
        self.fail_plan(reason)

    def fail_plan(self, reason: str) -> None:
        """Give the plan up and ask for a new one (once)."""
        if self.failed:
            return
        self.failed = True
        if self.plan_id is not None:
            self._c.tell(PlanChange(self.plan_id, PlanState.FAILED, reason))
        self.event("REPLAN", reason=reason)
        self._c.on_replan(reason)

    # --- timeouts ---------------------------------------------------------------------

    def arm(self, run: StepRun) -> None:
        """Start the timeout of a running step (for what is left of it)."""
        cancel_timer(run.timer)
        run.since = time.monotonic()
        if run.step.duration is None:
            return
        clock = self._c.clock
        wall = self._c.limits.wall_timeout(run.step.duration, clock)
        token = run.token
        run.timer = start_timer(  # elapsed and the limit are wall time
            wall - run.elapsed, self._c.post, lambda: self.timed_out(run, token, clock.robot(wall))
        )

    def timed_out(self, run: StepRun, token: int, limit: float) -> None:
        if run.token != token or run.state is not StepState.RUNNING:
            return
        self.fail(
            run,
            f"step {run.step.label} timed out: still running after {limit:g} s "
            f"(expected {run.step.duration:g} s)",
        )
