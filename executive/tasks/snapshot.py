"""What the task executor's status queries answer from: an immutable picture of the
tasks, the running functionalities and the permanently faulty components.

The executor's worker replaces the snapshot after every job and before every component
start, so a query never waits for the worker (which may be starting a component for
many seconds) and still sees which tasks that start is for. A task that was
just asked for is in the snapshot at once, before the worker takes it up.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

from executive.bus.api.tasks import ScheduleReply
from executive.bus.reports import ExecutorTask, ScheduledTask
from executive.tasks.task import TaskView


@dataclass(frozen=True)
class Snapshot:
    """The tasks (oldest first), the functionalities that run and the faulty ones."""

    tasks: tuple[TaskView, ...] = ()
    running: frozenset[str] = frozenset()
    faulty: frozenset[str] = frozenset()

    def adding(self, task: TaskView) -> Snapshot:
        """This snapshot with a newly asked-for task."""
        return dataclasses.replace(self, tasks=(*self.tasks, task))

    def task_list(self) -> list[ExecutorTask]:
        """Every task with its phase and configuration (newest last)."""
        return [t.status() for t in self.tasks]

    def schedule(self, now: float) -> ScheduleReply:
        """The running and waiting tasks in time (seconds from ``now``), the running
        and the faulty functionalities. A task that waits behind running ones starts
        when the last of them is due to end (or now, if they overran)."""
        rows = []
        ends: dict[str, float] = {}
        for t in self.tasks:  # oldest first: the tasks one waits behind come before it
            if t.phase.final:
                continue
            at = t.began if t.phase.holds else t.start_at
            start = (now if at is None else at) - now
            if not t.phase.holds and at is None and t.behind:
                start = max([0.0, *(ends[b] for b in t.behind if b in ends)])
            ends[t.id] = start + t.duration
            rows.append(ScheduledTask(**vars(t.status()), start=round(start, 3),
                                      end=round(start + t.duration, 3)))  # fmt: skip
        return ScheduleReply(rows, sorted(self.running), sorted(self.faulty))
