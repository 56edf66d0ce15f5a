"""One step of the plan being executed, as the plan executor tracks it.

Pure bookkeeping on the executor's thread: the step's state, the task carrying it out,
what its at-start effects changed (to take them back), and the stretch of its run that
counts towards its timeout.
"""

from __future__ import annotations

import enum
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

from executive.bus.clock import Clock
from executive.bus.timers import Timer, later
from executive.planning.partial_order import Step
from executive.planning.task_runner import Progress, StepReport, StepTask

Key = tuple[str, tuple[str, ...]]  # a fact's name and arguments


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

    def wall_timeout(self, duration: float, clock: Clock) -> float:
        """Return the timeout in wall-clock seconds: the duration and its relative share are
        robot time, the margin is wall time (starting processes and scheduling take as
        long at any time scale)."""
        return clock.wall(duration) + max(self.margin, clock.wall(self.relative * duration))


@dataclass
class StepRun:
    """What the executor knows about one step of the current plan.

    ``id`` is the identity of the step's run: the id of the DISPATCH event that began
    it. Every later event of the run (START, ADOPT, END, FAIL, CANCEL) names it as
    ``run``, also when a later plan continues the run as a step of its own; crash
    recovery matches a START with its end by it (:mod:`executive.planning.recovery`).
    """

    step: Step
    id: int | None = None
    state: StepState = StepState.PENDING
    task: StepTask | None = None
    report: StepReport | None = None
    started: bool = False  # at-start effects applied
    was: StepState = StepState.PENDING  # the state before a pause
    undo: dict[Key, bool | float | None] = field(default_factory=dict)
    elapsed: float = 0.0  # seconds run before the current stretch
    since: float = 0.0  # monotonic time the current stretch began
    timer: Timer | None = None
    token: int = 0
    held: tuple[Progress, Any] | None = None  # an end reported while paused, handled on resume

    def take_over(self, old: StepRun) -> None:
        """Continue the task of an earlier plan's step (same action and objects)."""
        self.id, self.state, self.task, self.report = old.id, old.state, old.task, old.report
        self.started, self.undo, self.was = old.started, old.undo, old.was
        self.elapsed, self.since, self.held = old.elapsed, old.since, old.held
        cancel_timer(old.timer)

    def touches(self, mentions: frozenset[Key]) -> bool:
        """Whether an effect still to come may change one of these facts."""
        effects = (
            self.step.end_effects
            if self.started
            else (*self.step.start_effects, *self.step.end_effects)
        )
        return any((e.name, e.args) in mentions for e in effects)

    def stop_clock(self) -> None:
        """End the current stretch: cancel the timeout, count the time run."""
        if self.timer is not None:
            cancel_timer(self.timer)
            self.timer = None
            self.elapsed += time.monotonic() - self.since


def start_timer(
    seconds: float, post: Callable[[Callable[[], None]], None], fn: Callable[[], None]
) -> Timer:
    """Run ``fn`` through ``post`` (on the executor's thread) after ``seconds``."""
    return later(seconds, lambda: post(fn))


def cancel_timer(timer: Timer | None) -> None:
    if timer is not None:
        timer.cancel()
