"""The plan executor's port to whatever carries out plan steps (the task executor).

The executor asks a :class:`TaskRunner` to run a step and gets a :class:`StepTask` it
may pause, resume or cancel; the runner reports how the step goes through the
:class:`StepReport` it was given, from any thread. Planning never imports the task
executor: :mod:`executive.tasks.plan_tasks` implements this port on top of it, and unit
tests use a scripted runner.
"""

from __future__ import annotations

import enum
from abc import ABC, abstractmethod
from collections.abc import Callable, Sequence
from typing import Any

from executive.planning.partial_order import Step


class Progress(enum.Enum):
    """What a runner reports about a step."""

    STARTED = "started"
    SUCCEEDED = "succeeded"  # with the behavior's result
    FAILED = "failed"  # with the reason


class StepReport:
    """How a runner reports on one step; call from any thread, late calls are ignored."""

    def __init__(self, post: Callable[[StepReport, Progress, Any], None]) -> None:
        self._send = post
        self.route: tuple[int | None, int, int] = (None, -1, -1)  # plan, step, token

    def _post(self, progress: Progress, value: Any) -> None:
        self._send(self, progress, value)

    def started(self) -> None:
        """The step's behavior runs (its configuration is ready)."""
        self._post(Progress.STARTED, None)

    def succeeded(self, result: Any = None) -> None:
        self._post(Progress.SUCCEEDED, result)

    def failed(self, reason: str) -> None:
        self._post(Progress.FAILED, reason)


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


class UnrunStep(StepTask):
    """A step that never began: its task could not be asked for, or no one could carry
    it out (the runner reports its failure); there is nothing to pause or cancel."""

    def pause(self) -> None:
        pass

    def resume(self) -> None:
        pass

    def cancel(self) -> None:
        pass


class TaskRunner(ABC):
    """Carries out plan steps: the task executor, or a scripted runner in unit tests."""

    @abstractmethod
    def run(self, step: Step, plan_id: int, report: StepReport) -> StepTask:
        """Start carrying out a step and return at once; report through ``report``."""

    def performer(self, action: str, args: Sequence[str]) -> str | None:
        """Who carries out a step of ``action`` with ``args``, for the record (the plan's
        events and ``dura plan show``): a fleet's robot; ``None`` by default (the robot
        itself)."""
        return None

    def upcoming(self, plan_id: int | None, steps: Sequence[Step]) -> None:
        """The steps of the current plan not dispatched yet (none: no plan, or it
        ended), told whenever they change: a runner may keep ready what they need.
        Returns at once; does nothing by default."""
        return
