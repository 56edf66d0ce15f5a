"""The world as the planner sees it: PDDL objects and facts (atoms and numeric values)."""

from __future__ import annotations

import json
from collections.abc import Iterable

from knowledge.records import Fact, TimedFact
from knowledge.tables.database import Database, dump


def _fact_value(text: str) -> bool | float:
    value = json.loads(text)
    return value if isinstance(value, bool) else float(value)


class WorldTables(Database):
    """The ``objects`` and ``facts`` tables."""

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
                        (f.name, " ".join(f.args), dump(f.value)),
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

    def add_timed_fact(self, timed: TimedFact) -> None:
        """Keep a fact that takes effect later (false: it stops holding then)."""
        f = timed.fact
        with self.transaction() as db:
            db.execute(
                "INSERT OR REPLACE INTO timed_facts(name, args, value, at) VALUES (?, ?, ?, ?)",
                (f.name, " ".join(f.args), dump(f.value), timed.at),
            )

    def timed_facts(self) -> list[TimedFact]:
        """The facts that take effect later, soonest first."""
        rows = self._query("SELECT * FROM timed_facts ORDER BY at, name, args")
        return [
            TimedFact(
                Fact(
                    r["name"],
                    tuple(r["args"].split()) if r["args"] else (),
                    _fact_value(r["value"]),
                ),
                r["at"],
            )
            for r in rows
        ]

    def apply_due_facts(self, now: float) -> list[TimedFact]:
        """Make the timed facts due by ``now`` facts of the world, in their order, in one
        transaction; the ones applied."""
        with self.transaction() as db:
            due = [t for t in self.timed_facts() if t.at <= now]
            for t in due:
                self.update_facts(add=[t.fact])
            db.execute("DELETE FROM timed_facts WHERE at <= ?", (now,))
        return due

    def clear_world(self) -> None:
        """Forget every object and fact (before loading a new initial state)."""
        with self.transaction() as db:
            db.execute("DELETE FROM facts")
            db.execute("DELETE FROM timed_facts")
            db.execute("DELETE FROM objects")
