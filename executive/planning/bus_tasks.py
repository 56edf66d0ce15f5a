"""Plan steps carried out by a task executor in another process: the plan executor's
:class:`~executive.planning.task_runner.TaskRunner` over the bus
(:mod:`executive.bus.api.steps`), for ``dura run --only planning`` and ``--without
tasks``.

Each step gets a run id of its own before it is asked for, so that no report of it is
missed; reports arrive on the progress topic and go to the step's
:class:`~executive.planning.task_runner.StepReport`. A step whose request fails (no task
executor answers), and a step running when the task executor's process vanishes, fails
with the reason, and the planner plans again; while no task executor is there, a step
waits for one (:data:`SERVER_WAIT`).
"""

from __future__ import annotations

import contextlib
import threading
import uuid
from collections.abc import Callable, Sequence
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
from executive.bus.keys import EXECUTIVE_ALIVE
from executive.bus.message import Message
from executive.bus.session import Bus
from executive.planning.partial_order import Step
from executive.planning.task_runner import Progress, StepReport, StepTask, TaskRunner
from knowledge.errors import DuraError

SERVER_WAIT = 30.0  # seconds a step waits for a task executor to serve it


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

    Args:
        bus: this process's bus session.
        interruptible: by action: may its task be paused?
        server: the liveliness token of the process whose task executor serves the steps:
            when it vanishes (the process stopped or died), every step still running
            there fails, and the planner plans again; a step asked for while it is not
            there waits for it (at most :data:`SERVER_WAIT`), so that a task executor
            restarting does not use up the goal's plans.
        on_server: told whether the server is there whenever that changes, before the
            steps running there fail (a fleet marks the robot unavailable first, so that
            the planner plans without it).
        fleet: the fleet whose plans' steps these are (a fleet's high level), if any.

    Call :meth:`close` to stop listening for reports.
    """

    def __init__(
        self,
        bus: Bus,
        interruptible: dict[str, bool],
        server: str = EXECUTIVE_ALIVE,
        on_server: Callable[[bool], None] | None = None,
        fleet: str | None = None,
    ) -> None:
        self.bus = bus
        self.fleet = fleet
        self.interruptible = dict(interruptible)
        self.server = server
        self.on_server = on_server
        self._reports: dict[str, StepReport] = {}
        self._lock = threading.Lock()
        self._served = threading.Event()  # the server's token is there
        self._subscriber = bus.subscribe(STEP_PROGRESS, self._on_progress)
        self._watch = bus.watch_alive(server, self._on_server)

    def close(self) -> None:
        self._subscriber.undeclare()
        self._watch.undeclare()

    def _on_server(self, _key: str, alive: bool) -> None:
        if self.on_server is not None:
            self.on_server(alive)
        if alive:
            self._served.set()
            return
        self._served.clear()
        with self._lock:
            lost, self._reports = list(self._reports.values()), {}
        for report in lost:
            report.failed(f"the task executor is gone ({self.server} vanished)")

    def upcoming(self, plan_id: int | None, steps: Sequence[Step]) -> None:
        request = StepsUpcoming(plan_id, [spec_of(s) for s in steps])
        threading.Thread(target=self._ask, args=(STEP_UPCOMING, request), daemon=True).start()

    def run(self, step: Step, plan_id: int, report: StepReport) -> StepTask:
        run = uuid.uuid4().hex
        with self._lock:
            self._reports[run] = report
        request = StepRun(run, plan_id, spec_of(step), self.fleet)
        if self._served.is_set():
            self._send(request)
        else:  # the plan executor goes on meanwhile (a cancel of the step, another step)
            threading.Thread(target=self._send_when_served, args=(request,), daemon=True).start()
        return _BusStep(self, run, self.interruptible.get(step.action, True))

    def _send(self, request: StepRun) -> None:
        try:
            STEP_RUN.call(self.bus, request)
        except DuraError as e:
            self._fail(request.run, f"the task executor did not take the step: {e}")

    def _send_when_served(self, request: StepRun) -> None:
        if not self._served.wait(SERVER_WAIT):
            self._fail(
                request.run,
                f"no task executor served the step within {SERVER_WAIT:g} s ({self.server} "
                "is not there)",
            )
            return
        with self._lock:
            wanted = request.run in self._reports  # not cancelled meanwhile
        if wanted:
            self._send(request)

    def _fail(self, run: str, reason: str) -> None:
        with self._lock:
            report = self._reports.pop(run, None)
        if report is not None:
            report.failed(reason)

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
