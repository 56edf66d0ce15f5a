"""The knowledge base: one SQLite file per robot, in WAL mode (thesis tables 5.1-5.3).

:class:`KnowledgeBase` is the one object every service and the CLI use. Its methods
come from the table groups in :mod:`knowledge.tables`, one module each: the connection
and transactions (:mod:`~knowledge.tables.database`), the event log, goals and plans,
tasks, the world's objects and facts, and components with their faults, achievements,
return values and parameters. It keeps more than 25 methods on purpose: callers change
rows of several groups in one transaction (``with kb.transaction():`` around a fact and
an event, a fault and a goal), and one object with one lock and one connection is what
makes that a single SQLite transaction. Each group's code lives and is read on its own.

Every public method that changes something is one transaction; several changes that
belong together go in one ``with kb.transaction():`` block. Readers (the CLI) open the
file read-only and never block the writer. A killed executive loses nothing that was
committed: SQLite's WAL survives the process. Goals and plans change state only along
their state machines (:data:`~knowledge.records.GOAL_TRANSITIONS`,
:data:`~knowledge.records.PLAN_TRANSITIONS`).
"""

from __future__ import annotations

from typing import Any

from knowledge.records import to_plain
from knowledge.tables.components import ComponentTables
from knowledge.tables.goals_and_plans import GoalTables
from knowledge.tables.tasks import TaskTables
from knowledge.tables.world import WorldTables


class KnowledgeBase(GoalTables, TaskTables, WorldTables, ComponentTables):
    """Typed access to a robot's knowledge base.

    Args:
        path: the database file; created (with its folder) unless ``readonly``.
        readonly: open for reading only (the CLI); the file must exist.
    """

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
