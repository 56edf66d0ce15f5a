"""A scripted task runner: the plan executor's collaborator in unit tests.

It stands in for the task executor (a separate part with its own tests), not for
robot hardware: each step is started at once and, unless the script says otherwise,
succeeds on a background thread after a short delay. Tests can hold steps and finish
or fail them by hand, deterministically.
"""

from __future__ import annotations

import threading
import time
from collections.abc import Collection, Mapping
from dataclasses import dataclass, field

from executive.planning.partial_order import Step
from executive.planning.plan_executor import StepReport, StepTask, TaskRunner


@dataclass
class ScriptedTask(StepTask):
    step: Step
    report: StepReport
    interruptible: bool = True
    calls: list[str] = field(default_factory=list)
    outcome: tuple[str | None] | None = None  # set when it finished while paused
    paused: bool = False

    def pause(self) -> None:
        self.calls.append("pause")
        self.paused = True

    def resume(self) -> None:
        self.calls.append("resume")
        self.paused = False
        if self.outcome is not None:
            self.end(self.outcome[0])

    def end(self, reason: str | None) -> None:
        """Report success (no reason) or failure; a paused task reports on resume."""
        if "cancel" in self.calls:
            return
        if self.paused:
            self.outcome = (reason,)
        elif reason is None:
            self.report.succeeded({"ok": True})
        else:
            self.report.failed(reason)

    def cancel(self) -> None:
        self.calls.append("cancel")


class ScriptedRunner(TaskRunner):
    """Starts every step; finishes it after ``delay`` seconds unless it is ``held``.

    Args:
        fail: step labels (``move_to(dock, lab)``) that fail, with the reason, the
            first time they run.
        held: action names whose steps wait for :meth:`finish` / :meth:`fail`.
        critical: action names whose tasks are not interruptible.
    """

    def __init__(
        self,
        *,
        fail: Mapping[str, str] | None = None,
        held: Collection[str] = (),
        critical: Collection[str] = (),
        delay: float = 0.01,
    ) -> None:
        self.fail_once = dict(fail or {})
        self.held = set(held)
        self.critical = set(critical)
        self.delay = delay
        self.tasks: list[ScriptedTask] = []
        self.changed = threading.Condition()

    def run(self, step: Step, plan_id: int, report: StepReport) -> StepTask:
        task = ScriptedTask(step, report, interruptible=step.action not in self.critical)
        with self.changed:
            self.tasks.append(task)
            self.changed.notify_all()
        report.started()
        if step.action not in self.held:
            reason = self.fail_once.pop(step.label, None)
            threading.Timer(self.delay, task.end, (reason,)).start()
        return task

    def wait_for(self, label: str, timeout: float = 30.0) -> ScriptedTask:
        """The newest task for a step label, waiting until one runs."""
        deadline = time.monotonic() + timeout
        with self.changed:
            while True:
                found = [t for t in self.tasks if t.step.label == label]
                if found:
                    return found[-1]
                left = deadline - time.monotonic()
                if left <= 0:
                    raise TimeoutError(f"no task for {label}; ran: {self.labels()}")
                self.changed.wait(left)

    def labels(self) -> list[str]:
        return [t.step.label for t in self.tasks]
