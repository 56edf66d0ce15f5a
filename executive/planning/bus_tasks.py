"""Plan steps carried out by a task executor in another process: the plan executer's
:class:`~executive.planning.task_runner.TaskRunner` over the bus
(:mod:`executive.bus.api.steps`), for ``dura run --only planning``.

Each step gets a run id of its own before it is asked for, so that no report of it is
missed; reports arrive on the progress topic and go to the step's
:class:`~executive.planning.task_runner.StepReport`. A step whose request fails (no task
executor answers) fails with the reason, and the planner plans again.
"""

from __future__ import annotations

import contextlib
import threading
import uuid
from collections.abc import Sequence
from typing import Any

from executive.bus.api.steps import (
    STEP_CONTROL,
    STEP_PROGRESS,
    STEP_RUN,
    STEP_UPCOMING,
    StepAction,
    StepControl,
    StepProgress,
    StepRun,
    StepSpec,
    StepsUpcoming,
)
from executive.bus.session import Bus, Message
from executive.planning.partial_order import Step
from executive.planning.task_runner import Progress, StepReport, StepTask, TaskRunner
from knowledge.errors import DuraError


def spec_of(step: Step) -> StepSpec:
    """What the task executor needs of a step."""
    return StepSpec(step.action, list(step.args), list(step.parameters), step.index, step.duration)


class _BusStep(StepTask):
    def __init__(self, runner: BusTasks, run: str, interruptible: bool) -> None:
        self.runner = runner
        self.run = run
        self.interruptible = interruptible

    def pause(self) -> None:
        self.runner._control(self.run, StepAction.PAUSE)

    def resume(self) -> None:
        self.runner._control(self.run, StepAction.RESUME)

    def cancel(self) -> None:
        self.runner._forget(self.run)  # no report is expected afterwards
        self.runner._control(self.run, StepAction.CANCEL)


class BusTasks(TaskRunner):
    """Runs plan steps on the task executor of another process, over ``bus``.

    Call :meth:`close` to stop listening for reports.
    """

    def __init__(self, bus: Bus, interruptible: dict[str, bool]) -> None:
        self.bus = bus
        self.interruptible = dict(interruptible)  # by action: may its task be paused?
        self._reports: dict[str, StepReport] = {}
        self._lock = threading.Lock()
        self._subscriber = bus.subscribe(STEP_PROGRESS, self._on_progress)

    def close(self) -> None:
        self._subscriber.undeclare()

    def upcoming(self, plan_id: int | None, steps: Sequence[Step]) -> None:
        request = StepsUpcoming(plan_id, [spec_of(s) for s in steps])
        threading.Thread(target=self._ask, args=(STEP_UPCOMING, request), daemon=True).start()

    def run(self, step: Step, plan_id: int, report: StepReport) -> StepTask:
        run = uuid.uuid4().hex
        with self._lock:
            self._reports[run] = report
        try:
            STEP_RUN.call(self.bus, StepRun(run, plan_id, spec_of(step)))
        except DuraError as e:
            self._forget(run)
            report.failed(f"the task executor did not take the step: {e}")
        return _BusStep(self, run, self.interruptible.get(step.action, True))

    def _on_progress(self, message: Message) -> None:
        try:
            progress = StepProgress.from_payload(message.payload)
            kind = Progress(progress.progress)
        except (DuraError, ValueError):
            return  # not a report this runner understands
        with self._lock:
            report = self._reports.get(progress.run)
            if report is not None and kind is not Progress.STARTED:
                del self._reports[progress.run]
        if report is None:
            return
        if kind is Progress.STARTED:
            report.started()
        elif kind is Progress.SUCCEEDED:
            report.succeeded(progress.value)
        else:
            report.failed(str(progress.value))

    def _forget(self, run: str) -> None:
        with self._lock:
            self._reports.pop(run, None)

    def _control(self, run: str, action: StepAction) -> None:
        self._ask(STEP_CONTROL, StepControl(run, action))

    def _ask(self, verb: Any, request: Any) -> None:
        # the step's end (or the task executor's absence) is reported otherwise
        with contextlib.suppress(DuraError):
            verb.call(self.bus, request)
