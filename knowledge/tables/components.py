"""What the robot remembers about its components across restarts: ratings, fault
counters and permanent faults, behaviour achievements (warm starts), return values and
parameters (thesis tables 5.2, 5.3)."""

from __future__ import annotations

import sqlite3
import time
from typing import Any

from knowledge.errors import KnowledgeError
from knowledge.records import ComponentRecord
from knowledge.tables.database import dump, load
from knowledge.tables.events import EventLog


class ComponentTables(EventLog):
    """The ``components``, ``achievements``, ``return_values`` and ``parameters`` tables."""

    # --- components and faults --------------------------------------------------------

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
                (component, key, dump(value), time.time()),
            )

    def achievements(self, component: str) -> dict[str, Any]:
        rows = self._query(
            "SELECT key, value FROM achievements WHERE component = ? ORDER BY key",
            (component,),
        )
        return {r["key"]: load(r["value"]) for r in rows}

    def clear_achievements(self, component: str) -> None:
        with self.transaction() as db:
            db.execute("DELETE FROM achievements WHERE component = ?", (component,))

    def store_return_value(self, component: str, value: Any, *, task_id: int | None = None) -> None:
        with self.transaction() as db:
            db.execute(
                "INSERT INTO return_values(task_id, component, value, stamp) VALUES (?, ?, ?, ?)",
                (task_id, component, dump(value), time.time()),
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
        return [load(r["value"]) for r in self._query(sql + " ORDER BY id", params)]

    def set_parameter(self, component: str, key: str, value: Any) -> None:
        with self.transaction() as db:
            db.execute(
                "INSERT OR REPLACE INTO parameters(component, key, value, updated) VALUES (?, ?, ?, ?)",
                (component, key, dump(value), time.time()),
            )
            self.log_event("PARAMETER", component, {"key": key, "value": value})

    def parameters(self, component: str) -> dict[str, Any]:
        rows = self._query(
            "SELECT key, value FROM parameters WHERE component = ? ORDER BY key",
            (component,),
        )
        return {r["key"]: load(r["value"]) for r in rows}
