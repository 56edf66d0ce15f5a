"""Supervision of running behaviors: a task's behavior is started on its ready
configuration, sent the task's goal, and watched until its result comes.

A failing behavior is restarted (warm, from its achievements) up to its
``max_restarts`` (:class:`~executive.tasks.faults.Faults` counts and decides), then its
task fails. A user pauses and resumes interruptible behaviors; the fault handling
interrupts a behavior while its configuration is repaired (paused if it is
reconfigurable, else stopped) and lets it go on afterwards.

Goal results arrive on the launcher's threads; they are posted to the executor's
worker, and a result of an older goal (before a restart) is ignored.
"""

from __future__ import annotations

import contextlib
import time
from collections.abc import Callable

from executive.bus.payloads import GoalResult
from executive.bus.states import GoalStatus, Lifecycle
from executive.runtime.launcher import Launcher
from executive.tasks.configurator import Configurator
from executive.tasks.faults import Faults, TaskAction
from executive.tasks.ledger import TaskLedger
from executive.tasks.task import Task, TaskEnd, TaskPhase
from knowledge.description import RobotDescription
from knowledge.errors import BusError, ComponentError, DuraError

End = Callable[[Task, TaskEnd, str], None]
Post = Callable[[Callable[[], None]], None]


class BehaviorSupervisor:
    """Starts, watches, restarts, pauses and resumes the tasks' behaviors.

    Args:
        end: ends a task (the executor then schedules the others).
        post: runs a job on the executor's worker.
    """

    def __init__(
        self,
        robot: RobotDescription,
        *,
        ledger: TaskLedger,
        launcher: Launcher,
        configurator: Configurator,
        faults: Faults,
        end: End,
        post: Post,
    ) -> None:
        self.robot = robot
        self.ledger = ledger
        self.launcher = launcher
        self.configurator = configurator
        self.faults = faults
        self._end = end
        self._post = post

    def launch(self, task: Task) -> None:
        """Start the task's behavior on its (ready) configuration and send it the goal."""
        if task.phase is not TaskPhase.STARTING:
            return  # started meanwhile (a nested schedule), or ended
        if not self.configurator.ready(task.providers.values()):
            return  # a provider is being repaired; the fault handling goes on from there
        state = self.configurator.start(task.behavior)
        if state.state is not Lifecycle.READY:
            self.failed(task, f"behavior {task.behavior} did not start: {state.reason}")
            return
        try:
            task.attempt += 1
            attempt = task.attempt
            handle = self.launcher.send_goal(task.behavior, task.goal, task_id=int(task.id))
        except ComponentError as e:
            self.failed(task, str(e))
            return
        task.handle = handle
        handle.add_done_callback(lambda r: self._post(lambda: self._on_result(task, attempt, r)))
        if task.began is None:
            task.began = time.time()
        self.ledger.set_phase(task, TaskPhase.PAUSED if task.paused_by_user else TaskPhase.RUNNING)
        if task.paused_by_user:
            with contextlib.suppress(ComponentError):
                self.launcher.pause(task.behavior)
        task.starts += 1
        self.ledger.event("TASK_STARTED", task, providers=task.providers, attempt=task.starts)

    def failed(self, task: Task, reason: str) -> None:
        """The task's behavior failed: restart it, or, beyond its restarts, fail the task."""
        decision = self.faults.fault(task.behavior, reason, [task.usage()])
        action = decision.tasks.get(task.id, TaskAction.FAIL)
        self.ledger.event("REPAIR", task, component=task.behavior, action=action.value)
        if action is TaskAction.RESTART:
            self.stop(task, "restarting after a failure")
            self.ledger.set_phase(task, TaskPhase.STARTING)
            task.restarts += 1
            self.ledger.event("TASK_RESTARTED", task, reason=reason, attempt=task.restarts)
            self.launch(task)
        else:
            self._end(task, TaskEnd.BEHAVIOR_FAILED, reason)

    def stop(self, task: Task, reason: str, *, wait: bool = True, keep: bool = False) -> None:
        """Stop the task's behavior; whatever its current goal reports is stale then.

        ``wait=False``: return once the goal is cancelled, the process stops meanwhile
        (its next start waits for that). ``keep``: the process goes on running, for a
        task to come."""
        task.attempt += 1
        if task.handle is not None and not task.handle.done():
            with contextlib.suppress(ComponentError, BusError):
                task.handle.cancel()
        task.handle = None
        if not keep:
            self.configurator.release(task.behavior, reason, wait=wait)

    def pause(self, task: Task) -> None:
        """A user pauses the task (now, or as soon as its behavior runs).

        Raises:
            DuraError: the task has ended, or its behavior is not interruptible.
        """
        if task.phase.final:
            raise DuraError(f"task {task.id} has ended ({task.phase.value})")
        if not self.robot.behaviors[task.behavior].interruptible:
            raise DuraError(f"task {task.id} ({task.behavior}) is not interruptible")
        task.paused_by_user = True
        if task.phase is TaskPhase.RUNNING:
            self.launcher.pause(task.behavior)
            self.ledger.set_phase(task, TaskPhase.PAUSED)
            self.ledger.event("TASK_PAUSED", task)

    def resume(self, task: Task) -> None:
        """A user resumes the task.

        Raises:
            DuraError: the task has ended.
        """
        if task.phase.final:
            raise DuraError(f"task {task.id} has ended ({task.phase.value})")
        task.paused_by_user = False
        if task.phase is TaskPhase.PAUSED:
            self.launcher.resume(task.behavior)
            self.ledger.set_phase(task, TaskPhase.RUNNING)
            self.ledger.event("TASK_RESUMED", task)

    def interrupt(self, task: Task, action: TaskAction, component: str) -> None:
        """Hold the task while ``component`` is repaired: pause or stop its behavior."""
        if action is TaskAction.PAUSE and task.phase is TaskPhase.RUNNING:
            with contextlib.suppress(ComponentError):
                self.launcher.pause(task.behavior)
            self.ledger.event("TASK_PAUSED", task, reason=f"{component} is being repaired")
        elif action is TaskAction.RESTART:  # the repair need not wait for the stop
            self.stop(task, f"{component} is being repaired", wait=False)
        task.repair = action
        self.ledger.set_phase(task, TaskPhase.REPAIRING)

    def go_on(self, task: Task) -> None:
        """A task whose configuration was repaired goes on: resume or start its behavior."""
        if task.phase is not TaskPhase.REPAIRING:
            return
        if not self.configurator.ready(task.providers.values()):
            return
        if (
            task.repair is TaskAction.PAUSE
            and self.launcher.state(task.behavior).state is Lifecycle.PAUSED
        ):
            self.launcher.resume(task.behavior)
            self.ledger.set_phase(task, TaskPhase.RUNNING)
            self.ledger.event("TASK_RESUMED", task, reason="configuration repaired")
            return
        self.ledger.set_phase(task, TaskPhase.STARTING)
        task.restarts += 1
        self.ledger.event(
            "TASK_RESTARTED", task, reason="configuration repaired", attempt=task.restarts
        )
        self.launch(task)

    def _on_result(self, task: Task, attempt: int, result: GoalResult) -> None:
        if attempt != task.attempt or task.phase.final or task.phase is TaskPhase.REPAIRING:
            return  # an older goal, or one we cancelled ourselves
        if result.status is GoalStatus.SUCCEEDED:
            task.result = dict(result.value)
            self._end(task, TaskEnd.SUCCEEDED, "")
        elif result.status is GoalStatus.CANCELLED:
            self._end(
                task, TaskEnd.BEHAVIOR_CANCELLED, result.reason or "the behavior cancelled it"
            )
        elif not result.fault:  # impossible in the world: the planner plans again
            self._end(task, TaskEnd.GOAL_FAILED, result.reason or "the goal failed")
        else:
            self.failed(task, result.reason or "the behavior failed")
