"""Goals and plans: the high level's rows, with the state machines of both.

A goal or plan changes state only along :data:`~knowledge.records.GOAL_TRANSITIONS` and
:data:`~knowledge.records.PLAN_TRANSITIONS`; anything else is refused inside the
transaction with a :class:`~knowledge.errors.KnowledgeError` that names the row and
both states (``goal 3: cannot go from cancelled to planned``), and nothing changes.
"""

from __future__ import annotations

import sqlite3
import time
from collections.abc import Iterable
from typing import Any

from knowledge.errors import KnowledgeError
from knowledge.records import STEP_STATES, Goal, GoalState, Plan, PlanState, PlanStep
from knowledge.tables.database import dump, load
from knowledge.tables.events import EventLog


class GoalTables(EventLog):
    """The ``goals``, ``plans`` and ``plan_steps`` tables."""

    # --- goals ------------------------------------------------------------------------

    @staticmethod
    def _goal(r: sqlite3.Row) -> Goal:
        return Goal(
            r["id"], r["expression"], GoalState(r["state"]), r["priority"], r["deadline"],
            r["source"], r["reason"], r["created"], r["updated"], bool(r["keep"]),
        )  # fmt: skip

    def add_goal(
        self,
        expression: str,
        *,
        priority: int = 0,
        deadline: float | None = None,
        source: str = "user",
        keep: bool = False,
    ) -> Goal:
        now = time.time()
        with self.transaction() as db:
            cursor = db.execute(
                "INSERT INTO goals(expression, state, priority, deadline, source, created,"
                " updated, keep) VALUES (?, ?, ?, ?, ?, ?, ?, ?)",
                (expression, GoalState.PENDING.value, priority, deadline, source, now, now,
                 int(keep)),
            )  # fmt: skip
            goal_id = int(cursor.lastrowid or 0)
            data = {"expression": expression, **({"keep": True} if keep else {})}
            self.log_event("GOAL_ADDED", f"goal {goal_id}", data)
        return self.goal(goal_id)

    def goal(self, goal_id: int) -> Goal:
        rows = self._query("SELECT * FROM goals WHERE id = ?", (goal_id,))
        if not rows:
            raise KnowledgeError(f"no goal {goal_id}")
        return self._goal(rows[0])

    def goals(
        self,
        states: Iterable[GoalState] | None = None,
        *,
        before: int = 0,
        limit: int | None = None,
    ) -> list[Goal]:
        """Goals in ``states`` (all without) with an id below ``before`` (unless 0),
        oldest first: all of them, or the newest ``limit`` (read as such: a long run's
        goals are many)."""
        where: list[str] = []
        params: list[Any] = []
        if states is not None:
            wanted = [s.value for s in states]
            where.append(f"state IN ({','.join('?' * len(wanted))})")
            params.extend(wanted)
        if before:
            where.append("id < ?")
            params.append(before)
        sql = "SELECT * FROM goals" + (f" WHERE {' AND '.join(where)}" if where else "")
        if limit is not None:
            sql = f"SELECT * FROM ({sql} ORDER BY id DESC LIMIT ?) ORDER BY id"
            params.append(limit)
        else:
            sql += " ORDER BY id"
        return [self._goal(r) for r in self._query(sql, params)]

    def goal_counts(self) -> dict[GoalState, int]:
        """How many goals are in each state (those with none are left out)."""
        rows = self._query("SELECT state, count(*) FROM goals GROUP BY state")
        return {GoalState(r[0]): int(r[1]) for r in rows}

    def open_goals(self) -> list[Goal]:
        return self.goals(s for s in GoalState if s.is_open)

    def kept_goals(self) -> list[Goal]:
        """The maintenance goals that hold now (achieved, with ``keep``): those re-posted
        when they stop holding. Asked on every change of facts, so it reads only them
        (an index), not every goal ever achieved."""
        sql = "SELECT * FROM goals WHERE keep = 1 AND state = ? ORDER BY id"
        return [self._goal(r) for r in self._query(sql, (GoalState.ACHIEVED.value,))]

    def set_goal_state(self, goal_id: int, state: GoalState, reason: str = "") -> Goal:
        """Move a goal to ``state`` and log ``GOAL_<STATE>``.

        Raises:
            KnowledgeError: no such goal, or its state may not change to ``state``.
        """
        with self.transaction() as db:
            row = db.execute("SELECT state, keep FROM goals WHERE id = ?", (goal_id,)).fetchone()
            if row is None:
                raise KnowledgeError(f"no goal {goal_id}")
            current = GoalState(row[0])
            if not current.can_become(state, keep=bool(row[1])):
                raise KnowledgeError(
                    f"goal {goal_id}: cannot go from {current.value} to {state.value}"
                )
            db.execute(
                "UPDATE goals SET state = ?, reason = ?, updated = ? WHERE id = ?",
                (state.value, reason, time.time(), goal_id),
            )
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
        """Store a new plan; any plan still pending or executing is superseded (its
        PLAN_STORED event says which it ``replaces``)."""
        now = time.time()
        steps = list(steps)
        with self.transaction() as db:
            replaced = [
                int(r[0])
                for r in db.execute(
                    "SELECT id FROM plans WHERE state IN (?, ?) ORDER BY id",
                    (PlanState.PENDING.value, PlanState.EXECUTING.value),
                )
            ]
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
                (PlanState.PENDING.value, engine, dump(list(goal_ids)), now, now),
            )
            plan_id = int(cursor.lastrowid or 0)
            db.executemany(
                "INSERT INTO plan_steps(plan_id, idx, action, args, start, duration)"
                " VALUES (?, ?, ?, ?, ?, ?)",
                [
                    (plan_id, s.index, s.action, dump(list(s.args)), s.start, s.duration)
                    for s in steps
                ],
            )
            stored: dict[str, Any] = {"steps": len(steps), "engine": engine}
            if replaced:
                stored["replaces"] = replaced[-1]
            self.log_event("PLAN_STORED", f"plan {plan_id}", stored)
        return self.plan(plan_id)

    def plan(self, plan_id: int) -> Plan:
        rows = self._query("SELECT * FROM plans WHERE id = ?", (plan_id,))
        if not rows:
            raise KnowledgeError(f"no plan {plan_id}")
        r = rows[0]
        rows = self._query("SELECT * FROM plan_steps WHERE plan_id = ? ORDER BY idx", (plan_id,))
        steps = tuple(
            PlanStep(
                s["idx"], s["action"], tuple(load(s["args"])), s["start"], s["duration"], s["state"]
            )
            for s in rows
        )
        return Plan(
            r["id"], PlanState(r["state"]), steps, r["engine"], tuple(load(r["goal_ids"])),
            r["reason"], r["created"], r["updated"],
        )  # fmt: skip

    def plans(self) -> list[Plan]:
        return [self.plan(r["id"]) for r in self._query("SELECT id FROM plans ORDER BY id")]

    def latest_plan(self) -> Plan | None:
        rows = self._query("SELECT id FROM plans ORDER BY id DESC LIMIT 1")
        return self.plan(rows[0]["id"]) if rows else None

    def set_plan_state(self, plan_id: int, state: PlanState, reason: str = "") -> Plan:
        """Move a plan to ``state``.

        Raises:
            KnowledgeError: no such plan, or its state may not change to ``state``.
        """
        with self.transaction() as db:
            row = db.execute("SELECT state FROM plans WHERE id = ?", (plan_id,)).fetchone()
            if row is None:
                raise KnowledgeError(f"no plan {plan_id}")
            current = PlanState(row[0])
            if not current.can_become(state):
                raise KnowledgeError(
                    f"plan {plan_id}: cannot go from {current.value} to {state.value}"
                )
            db.execute(
                "UPDATE plans SET state = ?, reason = ?, updated = ? WHERE id = ?",
                (state.value, reason, time.time(), plan_id),
            )
        return self.plan(plan_id)

    def set_step_state(self, plan_id: int, index: int, state: str) -> None:
        """Record what happened to a plan's step (the plan executor's thread writes it).

        Raises:
            KnowledgeError: an unknown state, or no such step.
        """
        if state not in STEP_STATES:
            raise KnowledgeError(f"plan {plan_id} step {index}: unknown step state '{state}'")
        with self.transaction() as db:
            changed = db.execute(
                "UPDATE plan_steps SET state = ? WHERE plan_id = ? AND idx = ?",
                (state, plan_id, index),
            ).rowcount
            if not changed:
                raise KnowledgeError(f"plan {plan_id} has no step {index}")
