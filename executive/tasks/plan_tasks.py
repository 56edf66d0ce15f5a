"""Plan steps as tasks: the plan executor's runner on the task executor.

A step of action ``a`` runs the task the robot description maps ``a`` to: its behavior,
with a goal whose fields are filled in from the step's objects (``move_to(dock, lab)``
→ ``{start: dock, target: lab}``), for the planned duration. The task executor reports
back; a task the scheduler cancels fails the step with the reason, and the planner
replans. A task the plan executor cancels itself (:attr:`TaskEnd.REQUESTER`) reports
nothing more.
"""

from __future__ import annotations

import contextlib
from collections.abc import Sequence
from typing import Any

from executive.planning.partial_order import Step
from executive.planning.task_runner import StepReport, StepTask, TaskRunner, UnrunStep
from executive.tasks.executor import TaskExecutor
from executive.tasks.task import TaskEnd, TaskHandle, TaskPhase
from knowledge.description import RobotDescription
from knowledge.errors import ConfigError, DuraError


def behavior_goal(robot: RobotDescription, step: Step) -> dict[str, Any]:
    """The goal a step's behavior gets: each field from a parameter, a property of the
    object a parameter names (``?to.pose``), or a constant.

    Raises:
        ConfigError: an object without the property a field takes.
    """
    bindings, objects = step.bindings, robot.objects
    return {
        name: arg.resolve(bindings, objects) for name, arg in robot.tasks[step.action].goal.items()
    }


class _StepTask(StepTask):
    def __init__(self, handle: TaskHandle, interruptible: bool) -> None:
        self.handle = handle
        self.interruptible = interruptible

    def pause(self) -> None:
        with contextlib.suppress(DuraError):  # it ended meanwhile: its report follows
            self.handle.pause()

    def resume(self) -> None:
        with contextlib.suppress(DuraError):
            self.handle.resume()

    def cancel(self) -> None:
        self.handle.cancel("the plan no longer needs it")


class PlanTasks(TaskRunner):
    """Runs plan steps on the task executor, and tells it which steps are to come (so
    that what they need keeps running between the steps)."""

    def __init__(self, tasks: TaskExecutor, robot: RobotDescription, source: str = "") -> None:
        self.tasks = tasks
        self.robot = robot
        self.source = source  # which high level's steps (the robot's own: "")

    def upcoming(self, plan_id: int | None, steps: Sequence[Step]) -> None:
        specs = [self.robot.tasks.get(s.action) for s in steps]
        self.tasks.expect([spec.behavior for spec in specs if spec is not None], self.source)

    def run(self, step: Step, plan_id: int | None, report: StepReport) -> StepTask:
        spec = self.robot.tasks[step.action]
        behavior = self.robot.behaviors[spec.behavior]
        seen: set[TaskPhase] = set()

        def changed(handle: TaskHandle) -> None:
            phase = handle.phase
            if phase is TaskPhase.RUNNING and TaskPhase.RUNNING not in seen:
                report.started()
            elif phase is TaskPhase.SUCCEEDED:
                report.succeeded(handle.result)
            elif phase is TaskPhase.FAILED:
                report.failed(handle.reason)
            elif phase is TaskPhase.CANCELLED and handle.end is not TaskEnd.REQUESTER:
                # cancelled by someone else than the plan (a user, the shutdown): the step
                # failed, and the planner plans again
                report.failed(f"cancelled: {handle.reason}")
            seen.add(phase)

        try:
            goal = behavior_goal(self.robot, step)
        except ConfigError as e:
            report.failed(str(e))  # the planner plans again, with the reason
            return UnrunStep()
        handle = self.tasks.start_task(
            behavior.name,
            goal,
            name=step.label,
            duration=step.duration,
            listener=changed,
            plan_id=plan_id,
            step=step.index,
        )
        return _StepTask(handle, behavior.interruptible)
