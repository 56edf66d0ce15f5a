"""Tasks: requests to run a behavior for a plan step (or for a user), with their results."""

from __future__ import annotations

import sqlite3
import time
from collections.abc import Iterable, Mapping
from typing import Any

from knowledge.errors import KnowledgeError
from knowledge.records import Task, TaskState
from knowledge.tables.database import dump, load
from knowledge.tables.events import EventLog


class TaskTables(EventLog):
    """The ``tasks`` table."""

    @staticmethod
    def _task(r: sqlite3.Row) -> Task:
        return Task(
            r["id"], r["action"], r["behavior"], load(r["args"]), TaskState(r["state"]),
            r["plan_id"], r["step"], load(r["result"]), r["reason"], r["created"], r["updated"],
        )  # fmt: skip

    def add_task(
        self,
        action: str,
        behavior: str,
        args: Mapping[str, Any] | None = None,
        *,
        plan_id: int | None = None,
        step: int | None = None,
    ) -> Task:
        now = time.time()
        with self.transaction() as db:
            cursor = db.execute(
                "INSERT INTO tasks(action, behavior, args, state, plan_id, step, created, updated)"
                " VALUES (?, ?, ?, ?, ?, ?, ?, ?)",
                (
                    action,
                    behavior,
                    dump(dict(args or {})),
                    TaskState.PENDING.value,
                    plan_id,
                    step,
                    now,
                    now,
                ),
            )
            task_id = int(cursor.lastrowid or 0)
        return self.task(task_id)

    def task(self, task_id: int) -> Task:
        rows = self._query("SELECT * FROM tasks WHERE id = ?", (task_id,))
        if not rows:
            raise KnowledgeError(f"no task {task_id}")
        return self._task(rows[0])

    def tasks(self, states: Iterable[TaskState] | None = None) -> list[Task]:
        if states is None:
            return [self._task(r) for r in self._query("SELECT * FROM tasks ORDER BY id")]
        wanted = [s.value for s in states]
        marks = ",".join("?" * len(wanted))
        sql = f"SELECT * FROM tasks WHERE state IN ({marks}) ORDER BY id"
        return [self._task(r) for r in self._query(sql, wanted)]

    def set_task_state(
        self, task_id: int, state: TaskState, *, reason: str = "", result: Any = None
    ) -> Task:
        with self.transaction() as db:
            cursor = db.execute(
                "UPDATE tasks SET state = ?, reason = ?, result = COALESCE(?, result), updated = ?"
                " WHERE id = ?",
                (
                    state.value,
                    reason,
                    None if result is None else dump(result),
                    time.time(),
                    task_id,
                ),
            )
            if cursor.rowcount == 0:
                raise KnowledgeError(f"no task {task_id}")
        return self.task(task_id)
