"""The execution trace: an append-only log of events, heard by listeners on commit."""

from __future__ import annotations

import time
from collections.abc import Collection, Mapping
from typing import Any

from knowledge.records import Event
from knowledge.tables.database import Database, dump, load


class EventLog(Database):
    """The ``events`` table."""

    def log_event(self, kind: str, subject: str = "", data: Mapping[str, Any] | None = None) -> int:
        """Append an event to the execution trace; returns its id. Stamped in its
        transaction, so that the log's order is its stamps' order."""
        payload = dict(data or {})
        with self.transaction() as db:
            stamp = time.time()
            cursor = db.execute(
                "INSERT INTO events(stamp, kind, subject, data) VALUES (?, ?, ?, ?)",
                (stamp, kind, subject, dump(payload)),
            )
            event_id = int(cursor.lastrowid or 0)
            if self._listeners:
                self._logged.append(Event(event_id, stamp, kind, subject, payload))
            return event_id

    def first_event(self, subject: str) -> int | None:
        """The id of the first event about ``subject`` (``goal 4``), if any (an index)."""
        rows = self._query("SELECT min(id) FROM events WHERE subject = ?", (subject,))
        return int(rows[0][0]) if rows and rows[0][0] is not None else None

    def events(
        self,
        *,
        after: int = 0,
        kind: str | None = None,
        limit: int | None = None,
        oldest: bool = False,
        kinds: Collection[str] = (),
        before: int = 0,
    ) -> list[Event]:
        """Events with an id above ``after`` (and below ``before``, unless 0), oldest
        first: the newest ``limit`` ones, or with ``oldest`` the oldest ``limit`` ones (to
        page forward through the log); only those of ``kind``, or of one of ``kinds``,
        if given."""
        sql = "SELECT * FROM events WHERE id > ?"
        params: list[Any] = [after]
        if before:
            sql += " AND id < ?"
            params.append(before)
        wanted = [*([kind] if kind is not None else []), *kinds]
        if wanted:
            sql += f" AND kind IN ({','.join('?' * len(wanted))})"
            params.extend(wanted)
        if limit is not None and not oldest:
            sql = f"SELECT * FROM ({sql} ORDER BY id DESC LIMIT ?) ORDER BY id"
            params.append(limit)
        elif limit is not None:
            sql += " ORDER BY id LIMIT ?"
            params.append(limit)
        else:
            sql += " ORDER BY id"
        return [
            Event(r["id"], r["stamp"], r["kind"], r["subject"], load(r["data"]))
            for r in self._query(sql, params)
        ]
