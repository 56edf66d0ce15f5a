"""Plan steps asked for over the bus: the task executor's side of
:mod:`executive.bus.api.steps`, for a high level in another process (the robot's own,
``dura run --only planning``, or a fleet's, ``dura fleet run``: the executive serves the
steps beside its own high level).

Each step runs through :class:`~executive.tasks.plan_tasks.PlanTasks`, exactly as it
does for a high level in the executive's own process; its reports go out on
:data:`~executive.bus.api.steps.STEP_PROGRESS`. A step the plan cancels itself reports
nothing more; one cancelled by anybody else fails.
"""

from __future__ import annotations

import contextlib
import threading
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
from executive.bus.service import Context, Service
from executive.bus.verb import Empty
from executive.planning.partial_order import Step
from executive.planning.task_runner import Progress, StepReport, StepTask
from executive.tasks.executor import TaskExecutor
from executive.tasks.plan_tasks import PlanTasks
from knowledge.errors import DuraError


def step_of(spec: StepSpec) -> Step:
    """The plan step a :class:`StepSpec` describes (what running its task needs)."""
    return Step(
        spec.index, spec.action, tuple(spec.args), tuple(spec.parameters), 0.0, spec.duration
    )


class StepService(Service):
    """Serves the step verbs on top of the task executor."""

    name = "plan steps"

    def __init__(self, context: Context, tasks: TaskExecutor) -> None:
        super().__init__(context)
        self.plan_tasks = PlanTasks(tasks, context.robot, source="bus")
        self._steps: dict[str, StepTask] = {}  # by run id, until the plan cancels them
        self._lock = threading.Lock()
        self._declared: list[Any] = []

    def on_activate(self) -> None:
        bus = self.context.bus
        self._declared = [
            STEP_RUN.serve(bus, self._run),
            STEP_CONTROL.serve(bus, self._control),
            STEP_UPCOMING.serve(bus, self._upcoming),
        ]

    def on_deactivate(self) -> None:
        for entity in self._declared:
            with contextlib.suppress(Exception):  # already closed with the bus
                entity.undeclare()
        self._declared = []

    def _run(self, request: StepRun) -> Empty:
        run, bus = request.run, self.context.bus

        ended = threading.Event()  # it may end before run() returns (a goal it cannot fill)

        def post(_: StepReport, progress: Progress, value: Any) -> None:
            if not bus.closed:
                bus.publish(STEP_PROGRESS, StepProgress(run, progress.value, value).to_payload())
            if progress is not Progress.STARTED:
                with self._lock:
                    ended.set()
                    self._steps.pop(run, None)

        # a fleet's plan is none of this robot's: its task belongs to no plan here
        plan_id = request.plan_id if request.fleet is None else None
        task = self.plan_tasks.run(step_of(request.step), plan_id, StepReport(post))
        with self._lock:
            if not ended.is_set():
                self._steps[run] = task
        return Empty()

    def _control(self, request: StepControl) -> Empty:
        with self._lock:
            task = self._steps.get(request.run)
            if request.action is StepAction.CANCEL:
                self._steps.pop(request.run, None)
        if task is None:
            if request.action is StepAction.CANCEL:
                return Empty()  # it ended meanwhile
            raise DuraError(f"no plan step '{request.run}' runs")
        if request.action is StepAction.PAUSE:
            task.pause()
        elif request.action is StepAction.RESUME:
            task.resume()
        else:
            task.cancel()
        return Empty()

    def _upcoming(self, request: StepsUpcoming) -> Empty:
        self.plan_tasks.upcoming(request.plan_id, [step_of(s) for s in request.steps])
        return Empty()
