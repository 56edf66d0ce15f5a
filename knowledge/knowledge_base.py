"""The knowledge base: one SQLite file per robot, in WAL mode.

Every public method that changes something is one transaction; several changes
that belong together go in one ``with kb.transaction():`` block. Readers (the
CLI) open the file read-only and never block the writer. A killed executive loses
nothing that was committed: SQLite's WAL survives the process.
"""

from __future__ import annotations

import json
import logging
import sqlite3
import threading
import time
from collections.abc import Callable, Iterable, Iterator, Mapping
from contextlib import contextmanager
from pathlib import Path
from typing import Any

from knowledge.errors import KnowledgeError
from knowledge.records import (
    ComponentRecord,
    Event,
    Fact,
    Goal,
    GoalState,
    Plan,
    PlanState,
    PlanStep,
    Task,
    TaskState,
    to_plain,
)
from knowledge.schema import MIGRATIONS, VERSION

log = logging.getLogger("dura.knowledge")


def _dump(value: Any) -> str:
    return json.dumps(value, sort_keys=True, separators=(",", ":"))


def _load(text: str | None) -> Any:
    return None if text is None else json.loads(text)


def _fact_value(text: str) -> bool | float:
    value = json.loads(text)
    return value if isinstance(value, bool) else float(value)


class KnowledgeBase:
    """Typed access to a robot's knowledge base.

    Args:
        path: the database file; created (with its folder) unless ``readonly``.
        readonly: open for reading only (the CLI); the file must exist.
    """

    def __init__(self, path: Path | str, *, readonly: bool = False) -> None:
        self.path = Path(path)
        self.readonly = readonly
        self._lock = threading.RLock()
        self._depth = 0
        self._listeners: list[Callable[[Event], None]] = []
        self._logged: list[Event] = []  # events of the open transaction
        try:
            if readonly:
                if not self.path.is_file():
                    raise KnowledgeError(f"{self.path}: no knowledge base here")
                uri = f"file:{self.path.resolve()}?mode=ro"
                self._db = sqlite3.connect(uri, uri=True, check_same_thread=False, timeout=5.0)
            else:
                self.path.parent.mkdir(parents=True, exist_ok=True)
                self._db = sqlite3.connect(
                    self.path,
                    check_same_thread=False,
                    timeout=5.0,
                    isolation_level=None,
                )
                self._db.execute("PRAGMA journal_mode=WAL")
                self._db.execute("PRAGMA synchronous=NORMAL")
            self._db.execute("PRAGMA foreign_keys=ON")
            self._migrate()
        except sqlite3.DatabaseError as e:
            raise KnowledgeError(f"{self.path}: cannot open knowledge base: {e}") from e

    # --- lifecycle --------------------------------------------------------------------

    def close(self) -> None:
        with self._lock:
            self._db.close()

    def __enter__(self) -> KnowledgeBase:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def _migrate(self) -> None:
        version = int(self._db.execute("PRAGMA user_version").fetchone()[0])
        if version > VERSION:
            raise KnowledgeError(
                f"{self.path}: schema version {version} is newer than this dura ({VERSION})"
            )
        if version == VERSION:
            return
        if self.readonly:
            raise KnowledgeError(f"{self.path}: schema version {version} needs a migration")
        with self.transaction():
            for statements in MIGRATIONS[version:]:
                for statement in statements:
                    self._db.execute(statement)
            self._db.execute(f"PRAGMA user_version={VERSION}")

    @contextmanager
    def transaction(self) -> Iterator[sqlite3.Connection]:
        """Group changes into one transaction (nested blocks join the outer one).

        Event listeners hear of the events it logged after it commits.
        """
        committed: list[Event] = []
        with self._lock:
            if self.readonly:
                raise KnowledgeError(f"{self.path}: opened read-only")
            outer = self._depth == 0
            if outer:
                self._db.execute("BEGIN IMMEDIATE")
            self._depth += 1
            try:
                yield self._db
            except BaseException:
                self._depth -= 1
                if outer:
                    self._db.execute("ROLLBACK")
                    self._logged.clear()
                raise
            self._depth -= 1
            if outer:
                self._db.execute("COMMIT")
                committed, self._logged = self._logged, []
        self._announce(committed)

    def _query(self, sql: str, params: Iterable[Any] = ()) -> list[sqlite3.Row]:
        with self._lock:
            cursor = self._db.execute(sql, tuple(params))
            cursor.row_factory = sqlite3.Row
            return list(cursor.fetchall())

    def integrity_check(self) -> str:
        return str(self._query("PRAGMA integrity_check")[0][0])

    @property
    def schema_version(self) -> int:
        return int(self._query("PRAGMA user_version")[0][0])

    # --- events -----------------------------------------------------------------------

    def add_listener(self, listener: Callable[[Event], None]) -> None:
        """Call ``listener`` with every event once the transaction that logged it commits.

        Listeners run on the committing thread, in order; one that raises is logged and
        does not stop the others (or the commit, which has happened).
        """
        with self._lock:
            self._listeners.append(listener)

    def _announce(self, events: list[Event]) -> None:
        for event in events:
            for listener in self._listeners:
                try:
                    listener(event)
                except Exception:
                    log.exception("event listener failed on %s", event.kind)

    def log_event(self, kind: str, subject: str = "", data: Mapping[str, Any] | None = None) -> int:
        """Append an event to the execution trace; returns its id."""
        stamp = time.time()
        payload = dict(data or {})
        with self.transaction() as db:
            cursor = db.execute(
                "INSERT INTO events(stamp, kind, subject, data) VALUES (?, ?, ?, ?)",
                (stamp, kind, subject, _dump(payload)),
            )
            event_id = int(cursor.lastrowid or 0)
            if self._listeners:
                self._logged.append(Event(event_id, stamp, kind, subject, payload))
            return event_id

    def events(
        self, *, after: int = 0, kind: str | None = None, limit: int | None = None
    ) -> list[Event]:
        """Events with an id above ``after``, oldest first (the newest ``limit`` ones)."""
        sql = "SELECT * FROM events WHERE id > ?"
        params: list[Any] = [after]
        if kind is not None:
            sql += " AND kind = ?"
            params.append(kind)
        if limit is not None:
            sql = f"SELECT * FROM ({sql} ORDER BY id DESC LIMIT ?) ORDER BY id"
            params.append(limit)
        else:
            sql += " ORDER BY id"
        return [
            Event(r["id"], r["stamp"], r["kind"], r["subject"], _load(r["data"]))
            for r in self._query(sql, params)
        ]

    # --- goals ------------------------------------------------------------------------

    @staticmethod
    def _goal(r: sqlite3.Row) -> Goal:
        return Goal(
            r["id"], r["expression"], GoalState(r["state"]), r["priority"], r["deadline"],
            r["source"], r["reason"], r["created"], r["updated"],
        )  # fmt: skip

    def add_goal(
        self,
        expression: str,
        *,
        priority: int = 0,
        deadline: float | None = None,
        source: str = "user",
    ) -> Goal:
        now = time.time()
        with self.transaction() as db:
            cursor = db.execute(
                "INSERT INTO goals(expression, state, priority, deadline, source, created, updated)"
                " VALUES (?, ?, ?, ?, ?, ?, ?)",
                (
                    expression,
                    GoalState.PENDING.value,
                    priority,
                    deadline,
                    source,
                    now,
                    now,
                ),
            )
            goal_id = int(cursor.lastrowid or 0)
            self.log_event("GOAL_ADDED", f"goal {goal_id}", {"expression": expression})
        return self.goal(goal_id)

    def goal(self, goal_id: int) -> Goal:
        rows = self._query("SELECT * FROM goals WHERE id = ?", (goal_id,))
        if not rows:
            raise KnowledgeError(f"no goal {goal_id}")
        return self._goal(rows[0])

    def goals(self, states: Iterable[GoalState] | None = None) -> list[Goal]:
        if states is None:
            return [self._goal(r) for r in self._query("SELECT * FROM goals ORDER BY id")]
        wanted = [s.value for s in states]
        marks = ",".join("?" * len(wanted))
        sql = f"SELECT * FROM goals WHERE state IN ({marks}) ORDER BY id"
        return [self._goal(r) for r in self._query(sql, wanted)]

    def open_goals(self) -> list[Goal]:
        return self.goals(s for s in GoalState if s.is_open)

    def set_goal_state(self, goal_id: int, state: GoalState, reason: str = "") -> Goal:
        with self.transaction() as db:
            cursor = db.execute(
                "UPDATE goals SET state = ?, reason = ?, updated = ? WHERE id = ?",
                (state.value, reason, time.time(), goal_id),
            )
            if cursor.rowcount == 0:
                raise KnowledgeError(f"no goal {goal_id}")
            self.log_event(
                f"GOAL_{state.name}",
                f"goal {goal_id}",
                {"reason": reason} if reason else {},
            )
        return self.goal(goal_id)

    # --- plans ------------------------------------------------------------------------

    def store_plan(
        self,
        steps: Iterable[PlanStep],
        *,
        engine: str = "",
        goal_ids: Iterable[int] = (),
    ) -> Plan:
        """Store a new plan; any plan still pending or executing is superseded."""
        now = time.time()
        steps = list(steps)
        with self.transaction() as db:
            db.execute(
                "UPDATE plans SET state = ?, updated = ? WHERE state IN (?, ?)",
                (
                    PlanState.SUPERSEDED.value,
                    now,
                    PlanState.PENDING.value,
                    PlanState.EXECUTING.value,
                ),
            )
            cursor = db.execute(
                "INSERT INTO plans(state, engine, goal_ids, created, updated) VALUES (?, ?, ?, ?, ?)",
                (PlanState.PENDING.value, engine, _dump(list(goal_ids)), now, now),
            )
            plan_id = int(cursor.lastrowid or 0)
            db.executemany(
                "INSERT INTO plan_steps(plan_id, idx, action, args, start, duration)"
                " VALUES (?, ?, ?, ?, ?, ?)",
                [
                    (
                        plan_id,
                        s.index,
                        s.action,
                        _dump(list(s.args)),
                        s.start,
                        s.duration,
                    )
                    for s in steps
                ],
            )
            self.log_event(
                "PLAN_STORED",
                f"plan {plan_id}",
                {"steps": len(steps), "engine": engine},
            )
        return self.plan(plan_id)

    def plan(self, plan_id: int) -> Plan:
        rows = self._query("SELECT * FROM plans WHERE id = ?", (plan_id,))
        if not rows:
            raise KnowledgeError(f"no plan {plan_id}")
        r = rows[0]
        steps = tuple(
            PlanStep(
                s["idx"],
                s["action"],
                tuple(_load(s["args"])),
                s["start"],
                s["duration"],
            )
            for s in self._query(
                "SELECT * FROM plan_steps WHERE plan_id = ? ORDER BY idx", (plan_id,)
            )
        )
        return Plan(
            r["id"], PlanState(r["state"]), steps, r["engine"], tuple(_load(r["goal_ids"])),
            r["reason"], r["created"], r["updated"],
        )  # fmt: skip

    def plans(self) -> list[Plan]:
        return [self.plan(r["id"]) for r in self._query("SELECT id FROM plans ORDER BY id")]

    def latest_plan(self) -> Plan | None:
        rows = self._query("SELECT id FROM plans ORDER BY id DESC LIMIT 1")
        return self.plan(rows[0]["id"]) if rows else None

    def set_plan_state(self, plan_id: int, state: PlanState, reason: str = "") -> Plan:
        with self.transaction() as db:
            cursor = db.execute(
                "UPDATE plans SET state = ?, reason = ?, updated = ? WHERE id = ?",
                (state.value, reason, time.time(), plan_id),
            )
            if cursor.rowcount == 0:
                raise KnowledgeError(f"no plan {plan_id}")
        return self.plan(plan_id)

    # --- tasks ------------------------------------------------------------------------

    @staticmethod
    def _task(r: sqlite3.Row) -> Task:
        return Task(
            r["id"], r["action"], r["behavior"], _load(r["args"]), TaskState(r["state"]),
            r["plan_id"], r["step"], _load(r["result"]), r["reason"], r["created"], r["updated"],
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
                    _dump(dict(args or {})),
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
                    None if result is None else _dump(result),
                    time.time(),
                    task_id,
                ),
            )
            if cursor.rowcount == 0:
                raise KnowledgeError(f"no task {task_id}")
        return self.task(task_id)

    # --- objects and facts ------------------------------------------------------------

    def add_object(self, name: str, type_name: str) -> None:
        with self.transaction() as db:
            db.execute(
                "INSERT OR REPLACE INTO objects(name, type) VALUES (?, ?)",
                (name, type_name),
            )

    def remove_object(self, name: str) -> None:
        with self.transaction() as db:
            db.execute("DELETE FROM objects WHERE name = ?", (name,))

    def objects(self) -> dict[str, str]:
        return {r["name"]: r["type"] for r in self._query("SELECT * FROM objects ORDER BY name")}

    def update_facts(self, *, add: Iterable[Fact] = (), remove: Iterable[Fact] = ()) -> None:
        """Apply removals, then additions, in one transaction (PDDL effect order)."""
        with self.transaction() as db:
            for f in remove:
                db.execute(
                    "DELETE FROM facts WHERE name = ? AND args = ?",
                    (f.name, " ".join(f.args)),
                )
            for f in add:
                if f.value is False:
                    db.execute(
                        "DELETE FROM facts WHERE name = ? AND args = ?",
                        (f.name, " ".join(f.args)),
                    )
                else:
                    db.execute(
                        "INSERT OR REPLACE INTO facts(name, args, value) VALUES (?, ?, ?)",
                        (f.name, " ".join(f.args), _dump(f.value)),
                    )

    def set_fact(self, fact: Fact) -> None:
        self.update_facts(add=[fact])

    def unset_fact(self, fact: Fact) -> None:
        self.update_facts(remove=[fact])

    def facts(self, name: str | None = None) -> list[Fact]:
        """Every true atom and numeric value, sorted (those of one predicate if named)."""
        if name is None:
            rows = self._query("SELECT * FROM facts ORDER BY name, args")
        else:
            rows = self._query("SELECT * FROM facts WHERE name = ? ORDER BY args", (name,))
        return [
            Fact(
                r["name"],
                tuple(r["args"].split()) if r["args"] else (),
                _fact_value(r["value"]),
            )
            for r in rows
        ]

    def clear_world(self) -> None:
        """Forget every object and fact (before loading a new initial state)."""
        with self.transaction() as db:
            db.execute("DELETE FROM facts")
            db.execute("DELETE FROM objects")

    # --- components -------------------------------------------------------------------

    @staticmethod
    def _component(r: sqlite3.Row) -> ComponentRecord:
        return ComponentRecord(
            r["name"],
            r["rating"],
            r["fault_count"],
            bool(r["permanent_fault"]),
            r["reason"],
            r["updated"],
        )

    def register_component(self, name: str, rating: float) -> ComponentRecord:
        """Make sure a component has a record; an existing one keeps its history."""
        with self.transaction() as db:
            db.execute(
                "INSERT OR IGNORE INTO components(name, rating, updated) VALUES (?, ?, ?)",
                (name, rating, time.time()),
            )
        return self.component(name)

    def component(self, name: str) -> ComponentRecord:
        rows = self._query("SELECT * FROM components WHERE name = ?", (name,))
        if not rows:
            raise KnowledgeError(f"no component '{name}' in the knowledge base")
        return self._component(rows[0])

    def components(self) -> list[ComponentRecord]:
        return [self._component(r) for r in self._query("SELECT * FROM components ORDER BY name")]

    def record_fault(self, name: str, reason: str, *, max_faults: int | None) -> ComponentRecord:
        """Count one fault; at ``max_faults`` (if any) the component becomes permanently faulty."""
        with self.transaction() as db:
            record = self.component(name)
            count = record.fault_count + 1
            permanent = record.permanent_fault or (max_faults is not None and count >= max_faults)
            db.execute(
                "UPDATE components SET fault_count = ?, permanent_fault = ?, reason = ?, updated = ?"
                " WHERE name = ?",
                (count, int(permanent), reason, time.time(), name),
            )
            self.log_event(
                "FAULT",
                name,
                {"count": count, "permanent": permanent, "reason": reason},
            )
            if permanent and not record.permanent_fault:
                self.log_event("PERMANENT_FAULT", name, {"reason": reason})
        return self.component(name)

    def mark_permanent_fault(self, name: str, reason: str) -> ComponentRecord:
        with self.transaction() as db:
            record = self.component(name)
            db.execute(
                "UPDATE components SET permanent_fault = 1, reason = ?, updated = ? WHERE name = ?",
                (reason, time.time(), name),
            )
            if not record.permanent_fault:
                self.log_event("PERMANENT_FAULT", name, {"reason": reason})
        return self.component(name)

    def reset_component(self, name: str) -> ComponentRecord:
        """Clear a component's faults after maintenance."""
        with self.transaction() as db:
            self.component(name)
            db.execute(
                "UPDATE components SET fault_count = 0, permanent_fault = 0, reason = '', updated = ?"
                " WHERE name = ?",
                (time.time(), name),
            )
            self.log_event("COMPONENT_RESET", name)
        return self.component(name)

    def set_rating(self, name: str, rating: float) -> ComponentRecord:
        with self.transaction() as db:
            self.component(name)
            db.execute(
                "UPDATE components SET rating = ?, updated = ? WHERE name = ?",
                (rating, time.time(), name),
            )
        return self.component(name)

    # --- achievements, return values, parameters --------------------------------------

    def set_achievement(self, component: str, key: str, value: Any) -> None:
        with self.transaction() as db:
            db.execute(
                "INSERT OR REPLACE INTO achievements(component, key, value, updated) VALUES (?, ?, ?, ?)",
                (component, key, _dump(value), time.time()),
            )

    def achievements(self, component: str) -> dict[str, Any]:
        rows = self._query(
            "SELECT key, value FROM achievements WHERE component = ? ORDER BY key",
            (component,),
        )
        return {r["key"]: _load(r["value"]) for r in rows}

    def clear_achievements(self, component: str) -> None:
        with self.transaction() as db:
            db.execute("DELETE FROM achievements WHERE component = ?", (component,))

    def store_return_value(self, component: str, value: Any, *, task_id: int | None = None) -> None:
        with self.transaction() as db:
            db.execute(
                "INSERT INTO return_values(task_id, component, value, stamp) VALUES (?, ?, ?, ?)",
                (task_id, component, _dump(value), time.time()),
            )

    def return_values(
        self, *, task_id: int | None = None, component: str | None = None
    ) -> list[Any]:
        sql, params = "SELECT value FROM return_values WHERE 1=1", list[Any]()
        if task_id is not None:
            sql += " AND task_id = ?"
            params.append(task_id)
        if component is not None:
            sql += " AND component = ?"
            params.append(component)
        return [_load(r["value"]) for r in self._query(sql + " ORDER BY id", params)]

    def set_parameter(self, component: str, key: str, value: Any) -> None:
        with self.transaction() as db:
            db.execute(
                "INSERT OR REPLACE INTO parameters(component, key, value, updated) VALUES (?, ?, ?, ?)",
                (component, key, _dump(value), time.time()),
            )
            self.log_event("PARAMETER", component, {"key": key, "value": value})

    def parameters(self, component: str) -> dict[str, Any]:
        rows = self._query(
            "SELECT key, value FROM parameters WHERE component = ? ORDER BY key",
            (component,),
        )
        return {r["key"]: _load(r["value"]) for r in rows}

    # --- everything -------------------------------------------------------------------

    def snapshot(self, *, events: int = 20) -> dict[str, Any]:
        """The whole knowledge base as plain data (for ``dura kb show``)."""
        return {
            "path": str(self.path),
            "schema_version": self.schema_version,
            "goals": [to_plain(g) for g in self.goals()],
            "plans": [to_plain(p) for p in self.plans()],
            "tasks": [to_plain(t) for t in self.tasks()],
            "objects": self.objects(),
            "facts": [str(f) for f in self.facts()],
            "components": [to_plain(c) for c in self.components()],
            "parameters": {
                r["component"]: self.parameters(r["component"])
                for r in self._query("SELECT DISTINCT component FROM parameters ORDER BY component")
            },
            "achievements": {
                r["component"]: self.achievements(r["component"])
                for r in self._query(
                    "SELECT DISTINCT component FROM achievements ORDER BY component"
                )
            },
            "events": [to_plain(e) for e in self.events(limit=events)],
        }
