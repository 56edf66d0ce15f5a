"""The task executor's API: tasks by hand, the schedule, faults and resets of components.

A task travels as an :class:`~executive.bus.reports.ExecutorTask` (the executor's view
of it; the knowledge base's row is :class:`knowledge.records.Task`), placed in time as a
:class:`~executive.bus.reports.ScheduledTask`.
"""

from __future__ import annotations

from dataclasses import field
from typing import Annotated

from executive.bus.api.free_form import GoalFields
from executive.bus.keys import api
from executive.bus.payloads import ComponentState
from executive.bus.reports import ExecutorTask, ScheduledTask
from executive.bus.schema import Between, Payload, Text
from executive.bus.verb import Empty, Verb
from knowledge.record_class import record

Seconds = Annotated[float, Between(0.0, 1e9)]


@record
class TaskStart(Payload):
    """A task of the robot (or a behavior) with its goal fields and constraints; times
    are seconds from now, ``together`` lists waiting tasks to start with."""

    task: Text
    goal: GoalFields = field(default_factory=dict)
    duration: Seconds | None = None
    earliest: Seconds | None = None
    deadline: Seconds | None = None
    together: list[str] = field(default_factory=list)

    @property
    def label(self) -> str:
        """The task's name in lists and logs, by its goal fields as a plan step is by its
        objects: ``move_to(start=dock, target=lab)``."""
        fields = ", ".join(f"{key}={value}" for key, value in self.goal.items())
        return f"{self.task}({fields})" if fields else self.task


@record
class TaskStarted(Payload):
    """The started task's id and the behavior that carries it out."""

    id: str
    behavior: str


@record
class TaskId(Payload):
    """A task, by id."""

    id: Text


@record
class TaskReply(Payload):
    """A task as the executor holds it."""

    task: ExecutorTask


@record
class TasksReply(Payload):
    """Every task as the executor holds it."""

    tasks: list[ExecutorTask]


@record
class ScheduleReply(Payload):
    """Waiting and running tasks in time, the running and the permanently faulty
    functionalities."""

    tasks: list[ScheduledTask]
    running: list[str]
    faulty: list[str]


@record
class ComponentFault(Payload):
    """A fault of a component reported by a repair rule or a user."""

    name: Text
    reason: str = ""


@record
class FaultReply(Payload):
    """The component's state and its faults."""

    state: ComponentState
    faults: int
    permanent: bool


@record
class ComponentName(Payload):
    """A component, by name."""

    name: Text


@record
class ResetReply(Payload):
    """The functionalities usable again."""

    usable: list[str]


TASK_START = Verb(api("task/start"), TaskStart, TaskStarted)
TASK_LIST = Verb(api("task/list"), Empty, TasksReply)
TASK_STOP = Verb(api("task/stop"), TaskId, TaskReply)
TASK_PAUSE = Verb(api("task/pause"), TaskId, TaskReply)
TASK_RESUME = Verb(api("task/resume"), TaskId, TaskReply)
SCHEDULE_SHOW = Verb(api("schedule/show"), Empty, ScheduleReply)
COMPONENT_RESTART = Verb(api("component/restart"), ComponentFault, FaultReply)
COMPONENT_FAULT = Verb(api("component/fault"), ComponentFault, FaultReply)
COMPONENT_RESET = Verb(api("component/reset"), ComponentName, ResetReply)
