"""The knowledge base's SQLite connection: one file per robot, in WAL mode.

Every public method of the tables that changes something is one transaction; several
changes that belong together go in one ``with kb.transaction():`` block. Readers (the
CLI) open the file read-only and never block the writer. A killed executive loses
nothing that was committed: SQLite's WAL survives the process.
"""

from __future__ import annotations

import json
import logging
import sqlite3
import threading
from collections.abc import Callable, Iterable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any, Self

from knowledge.errors import KnowledgeError
from knowledge.health import check
from knowledge.records import Event
from knowledge.schema import MIGRATIONS, VERSION

log = logging.getLogger("dura.knowledge")


def dump(value: Any) -> str:
    """A value as the JSON text a column holds."""
    return json.dumps(value, sort_keys=True, separators=(",", ":"))


def load(text: str | None) -> Any:
    """A JSON column's value (``None`` for NULL)."""
    return None if text is None else json.loads(text)


class Database:
    """The connection, its migrations and transactions, and the commit listeners.

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
        if self.path.exists():  # never start afresh over a damaged file: that loses it all
            health = check(self.path, thorough=False)
            if not health.sound:
                raise KnowledgeError(health.summary())
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

    def __enter__(self) -> Self:
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

    # --- transactions -----------------------------------------------------------------

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

    # --- listeners --------------------------------------------------------------------

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
