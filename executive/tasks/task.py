"""A task of the task executor: its phases, why it ended, its state and its views.

A :class:`Task` is the executor's own record of one task: mutable, and touched only by
the executor's worker thread. Everybody else sees a task through a :class:`TaskView`
(a frozen copy taken on that thread: the status queries answer from those, and the
decisions read them) or through the :class:`TaskHandle` its requester holds.
"""

from __future__ import annotations

import enum
import threading
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any, Protocol

from executive.bus.reports import ExecutorTask
from executive.runtime.launcher import GoalHandle
from executive.tasks.faults import TaskAction, TaskUsage
from knowledge.records import TaskState


class TaskPhase(enum.Enum):
    """Where a task is, as the executor sees it."""

    WAITING = "waiting"  # asked for its configuration
    STARTING = "starting"  # configuration and behavior coming up
    RUNNING = "running"
    PAUSED = "paused"
    REPAIRING = "repairing"  # its configuration is being repaired after a fault
    SUCCEEDED = "succeeded"
    FAILED = "failed"
    CANCELLED = "cancelled"

    @property
    def final(self) -> bool:
        return self in (TaskPhase.SUCCEEDED, TaskPhase.FAILED, TaskPhase.CANCELLED)

    @property
    def holds(self) -> bool:
        """It holds a configuration."""
        return self in (
            TaskPhase.STARTING,
            TaskPhase.RUNNING,
            TaskPhase.PAUSED,
            TaskPhase.REPAIRING,
        )


class TaskEnd(enum.Enum):
    """Why a task ended, for code to branch on (a task's ``reason`` says it to people)."""

    SUCCEEDED = "succeeded"  # its behavior achieved the goal
    BEHAVIOR_FAILED = "behavior_failed"  # its behavior failed beyond its restarts, or never ran
    GOAL_FAILED = "goal_failed"  # its behavior found the goal impossible in the world (no fault)
    BEHAVIOR_CANCELLED = "behavior_cancelled"  # its behavior gave the goal up
    BEHAVIOR_FAULTY = "behavior_faulty"  # its behavior was marked permanently faulty
    UNSCHEDULABLE = "unschedulable"  # the scheduler found no place for it
    REQUESTER = "requester"  # who asked for it cancelled it (a plan that no longer needs it)
    USER = "user"  # stopped by hand (``dura task stop``)
    SHUTDOWN = "shutdown"  # the executive stops

    @property
    def phase(self) -> TaskPhase:
        """The final phase a task ends in for this cause."""
        if self is TaskEnd.SUCCEEDED:
            return TaskPhase.SUCCEEDED
        if self in (TaskEnd.BEHAVIOR_CANCELLED, TaskEnd.REQUESTER, TaskEnd.USER, TaskEnd.SHUTDOWN):
            return TaskPhase.CANCELLED
        return TaskPhase.FAILED


KB_STATE = {
    TaskPhase.WAITING: TaskState.PENDING,
    TaskPhase.STARTING: TaskState.SCHEDULED,
    TaskPhase.RUNNING: TaskState.RUNNING,
    TaskPhase.PAUSED: TaskState.PAUSED,
    TaskPhase.REPAIRING: TaskState.RUNNING,
    TaskPhase.SUCCEEDED: TaskState.SUCCEEDED,
    TaskPhase.FAILED: TaskState.FAILED,
    TaskPhase.CANCELLED: TaskState.CANCELLED,
}


@dataclass(frozen=True)
class TaskView:
    """A task as it stood when the executor's worker last looked: what the decisions
    read and the status queries show. Times are epoch seconds.

    Args:
        earliest: the earliest start.
        deadline: the latest end, or ``None``.
        together: ids of tasks to start at the same time as this one.
        providers: capability → functionality, while it holds a configuration (and
            what it last held, after it ended).
        began: when its behavior first ran.
        start_at: its scheduled start, while it waits for a later one.
        behind: the running tasks it waits for, while it waits behind them.
    """

    id: str
    behavior: str
    duration: float
    name: str = ""
    goal: Mapping[str, Any] = field(default_factory=dict)
    earliest: float = 0.0
    deadline: float | None = None
    together: tuple[str, ...] = ()
    phase: TaskPhase = TaskPhase.WAITING
    providers: Mapping[str, str] = field(default_factory=dict)
    began: float | None = None
    start_at: float | None = None
    behind: tuple[str, ...] = ()
    reason: str = ""
    end: TaskEnd | None = None
    result: Mapping[str, Any] | None = None

    def status(self) -> ExecutorTask:
        """The task as ``task/list`` shows it."""
        return ExecutorTask(
            id=self.id,
            name=self.name or self.behavior,
            behavior=self.behavior,
            goal=dict(self.goal),
            state=self.phase.value,
            providers=dict(self.providers),
            functionalities=tuple(sorted(set(self.providers.values()))),
            duration=self.duration,
            reason=self.reason,
            ended_by=None if self.end is None else self.end.value,
            result=None if self.result is None else dict(self.result),
        )


Listener = Callable[["TaskHandle"], None]


@dataclass
class Task:
    """The executor's record of a task (its worker thread's alone)."""

    id: str
    name: str  # the action (or the behavior, for a task a user started)
    behavior: str
    goal: dict[str, Any]
    duration: float
    earliest: float  # epoch seconds
    deadline: float | None  # epoch seconds
    together: tuple[str, ...]
    listener: Listener | None
    phase: TaskPhase = TaskPhase.WAITING
    providers: dict[str, str] = field(default_factory=dict)
    handle: GoalHandle | None = None
    attempt: int = 0  # goals sent; a result of an older one is ignored
    starts: int = 0  # times its behavior was started (TASK_STARTED attempt 1, 2, 3)
    restarts: int = 0  # times it was started again (TASK_RESTARTED attempt 1, 2, 3)
    began: float | None = None  # when the behavior first ran
    paused_by_user: bool = False
    reason: str = ""
    end: TaskEnd | None = None
    result: dict[str, Any] | None = None
    done: threading.Event = field(default_factory=threading.Event)
    start_at: float | None = None  # scheduled start (epoch), while waiting
    behind: tuple[str, ...] = ()  # the running tasks it waits for, while waiting
    repair: TaskAction = TaskAction.RESTART  # how it goes on after a repair
    plan_id: int | None = None  # the plan whose step it runs (its failure: a new plan)

    def usage(self) -> TaskUsage:
        """What fault handling needs to know of it."""
        return TaskUsage(self.id, self.behavior, frozenset(self.providers.values()))

    def view(self) -> TaskView:
        # the goal and a result are never changed once set, so the view may share them
        return TaskView(
            id=self.id,
            behavior=self.behavior,
            duration=self.duration,
            name=self.name,
            goal=self.goal,
            earliest=self.earliest,
            deadline=self.deadline,
            together=self.together,
            phase=self.phase,
            providers=dict(self.providers),
            began=self.began,
            start_at=self.start_at,
            behind=self.behind,
            reason=self.reason,
            end=self.end,
            result=self.result,
        )


class TaskControl(Protocol):
    """What a handle asks of the executor."""

    def pause(self, task_id: str) -> None: ...

    def resume(self, task_id: str) -> None: ...

    def cancel(self, task_id: str, reason: str = "cancelled") -> None: ...


class TaskHandle:
    """A task as its requester sees it; methods return at once (the executor acts)."""

    def __init__(self, control: TaskControl, task: Task) -> None:
        self._control = control
        self._task = task

    @property
    def id(self) -> str:
        return self._task.id

    @property
    def phase(self) -> TaskPhase:
        return self._task.phase

    @property
    def end(self) -> TaskEnd | None:
        """Why it ended (``None`` while it has not)."""
        return self._task.end

    @property
    def reason(self) -> str:
        return self._task.reason

    @property
    def result(self) -> dict[str, Any] | None:
        return self._task.result

    @property
    def providers(self) -> dict[str, str]:
        return dict(self._task.providers)

    def pause(self) -> None:
        self._control.pause(self.id)

    def resume(self) -> None:
        self._control.resume(self.id)

    def cancel(self, reason: str = "cancelled") -> None:
        """End the task: its requester no longer needs it (:attr:`TaskEnd.REQUESTER`)."""
        self._control.cancel(self.id, reason)

    def wait(self, timeout: float | None = None) -> bool:
        """Wait until the task ended; whether it did."""
        return self._task.done.wait(timeout)
