"""The task executor's tasks and their record: phases in the knowledge base, events,
and the requester's listener told of every change.

Every part of the executor changes a task's phase through :meth:`TaskLedger.set_phase`,
so the knowledge base (TASK_* events, task states) and the requester never miss a
step. The ledger belongs to the executor's worker thread.
"""

from __future__ import annotations

import contextlib
import logging
from collections import deque
from collections.abc import Iterator
from typing import Any

from executive.tasks.task import KB_STATE, Task, TaskControl, TaskHandle, TaskPhase, TaskView
from knowledge.errors import KnowledgeError
from knowledge.knowledge_base import KnowledgeBase

log = logging.getLogger("dura.task_executor")

KEPT_ENDED = 50  # ended tasks kept in memory (and listed); the knowledge base has all


class TaskLedger:
    """The tasks by id, in the order they were asked for.

    Args:
        kb: where phases and events are recorded.
        control: what the handles given to listeners act through.
    """

    def __init__(self, kb: KnowledgeBase, control: TaskControl) -> None:
        self.kb = kb
        self._control = control
        self._tasks: dict[str, Task] = {}
        self._ended: deque[str] = deque()  # ended tasks still kept, oldest first

    def __iter__(self) -> Iterator[Task]:
        return iter(list(self._tasks.values()))  # a copy: callers end and add tasks

    def add(self, task: Task) -> None:
        self._tasks[task.id] = task
        self.event("TASK_REQUESTED", task, goal=task.goal, duration=task.duration)

    def get(self, task_id: str) -> Task:
        """The task of that id.

        Raises:
            KnowledgeError: no such task.
        """
        task = self._tasks.get(str(task_id))
        if task is None:
            raise KnowledgeError(f"no task {task_id}")
        return task

    def find(self, task_id: str) -> Task | None:
        return self._tasks.get(str(task_id))

    def in_phase(self, phase: TaskPhase) -> list[Task]:
        return [t for t in self._tasks.values() if t.phase is phase]

    def holding(self) -> list[Task]:
        """The tasks that hold a configuration."""
        return [t for t in self._tasks.values() if t.phase.holds]

    def views(self) -> list[TaskView]:
        return [t.view() for t in self._tasks.values()]

    def set_phase(
        self, task: Task, phase: TaskPhase, *, reason: str = "", result: Any = None
    ) -> None:
        """Move a task to a phase, record it, and tell its requester. Of the ended tasks
        the newest :data:`KEPT_ENDED` stay listed; the knowledge base keeps them all."""
        task.phase = phase
        if phase.final and task.id in self._tasks and task.id not in self._ended:
            self._ended.append(task.id)
            while len(self._ended) > KEPT_ENDED:
                self._tasks.pop(self._ended.popleft(), None)
        with contextlib.suppress(KnowledgeError):
            self.kb.set_task_state(int(task.id), KB_STATE[phase], reason=reason, result=result)
        if task.listener is not None:
            try:
                task.listener(TaskHandle(self._control, task))
            except Exception:  # a requester's bug must not stop the executor
                log.exception("task listener failed")

    def event(self, kind: str, task: Task, **data: Any) -> None:
        """Log an event of a task in the knowledge base."""
        self.kb.log_event(kind, f"task {task.id} {task.name}", {"behavior": task.behavior, **data})
