"""Whether a knowledge base file is sound, and a repair that keeps whatever can be read.

The executive refuses to start on a knowledge base that is not sound (an emptied file,
a missing table, a malformed page), with one line naming the file: starting afresh
would silently lose goals and fault counters. ``dura kb check`` says what is wrong;
``dura kb repair`` moves the damaged file aside (never deleting it) and writes a new
one with every row that can still be read, table by table and, past a malformed page,
row by row.
"""

from __future__ import annotations

import contextlib
import functools
import sqlite3
import time
from dataclasses import dataclass, field
from pathlib import Path

from knowledge.schema import MIGRATIONS, VERSION


@functools.cache
def tables() -> dict[str, tuple[str, ...]]:
    """Every table the schema makes, with its columns (read from the schema itself)."""
    with contextlib.closing(sqlite3.connect(":memory:")) as db:
        for migration in MIGRATIONS:
            for statement in migration:
                db.execute(statement)
        names = db.execute(
            "SELECT name FROM sqlite_master WHERE type = 'table' AND name NOT LIKE 'sqlite_%'"
        ).fetchall()
        return {
            name: tuple(c[1] for c in db.execute(f"PRAGMA table_info({name})")) for (name,) in names
        }


@dataclass(frozen=True)
class Health:
    """What is wrong with a knowledge base file (nothing, when ``problems`` is empty)."""

    path: Path
    problems: tuple[str, ...] = ()
    rows: dict[str, int] = field(default_factory=dict)  # readable rows per table

    @property
    def sound(self) -> bool:
        return not self.problems

    def summary(self) -> str:
        """One line for a person: the first problem, and how to repair it."""
        if self.sound:
            return f"{self.path}: sound"
        more = f" (and {len(self.problems) - 1} more)" if len(self.problems) > 1 else ""
        return (
            f"{self.path}: {self.problems[0]}{more}; 'dura kb check --db {self.path}' "
            "tells more, 'dura kb repair --db ...' keeps what can be read"
        )


def check(path: Path, *, thorough: bool = True) -> Health:
    """Look at a knowledge base file without changing it.

    ``thorough`` reads every page (``PRAGMA integrity_check``); otherwise the quick check,
    which is what the executive runs at each start.
    """
    path = Path(path)
    if not path.exists():
        return Health(path, ("no such file",))
    if path.stat().st_size == 0:
        return Health(path, ("the file is empty (0 bytes): not a knowledge base",))
    problems: list[str] = []
    rows: dict[str, int] = {}
    try:
        with contextlib.closing(_open_readonly(path)) as db:
            version = int(db.execute("PRAGMA user_version").fetchone()[0])
            pragma = "integrity_check" if thorough else "quick_check"
            verdicts = [str(r[0]) for r in db.execute(f"PRAGMA {pragma}(20)")]
            if verdicts != ["ok"]:
                lines = [line.strip() for v in verdicts for line in v.splitlines()]
                problems.append("damaged: " + "; ".join([line for line in lines if line][:3]))
            present = {
                r[0] for r in db.execute("SELECT name FROM sqlite_master WHERE type = 'table'")
            }
            missing = [t for t in tables() if t not in present]
            if missing and version == VERSION:
                problems.append(f"missing tables: {', '.join(missing)}")
            for table in tables():
                if table in present:
                    with contextlib.suppress(sqlite3.DatabaseError):
                        rows[table] = int(db.execute(f"SELECT count(*) FROM {table}").fetchone()[0])
    except sqlite3.DatabaseError as e:
        problems.append(f"not readable as a knowledge base ({e})")
    return Health(path, tuple(problems), rows)


def _open_readonly(path: Path) -> sqlite3.Connection:
    return sqlite3.connect(f"file:{path.resolve()}?mode=ro", uri=True, timeout=5.0)


@dataclass(frozen=True)
class Repair:
    """What a repair kept and lost, and where the damaged file went."""

    path: Path
    kept_aside: Path
    kept: dict[str, int]
    lost: dict[str, int]


def repair(path: Path) -> Repair:
    """Move a damaged knowledge base aside and write a sound one with every readable row.

    Raises:
        OSError: the file cannot be moved or written.
    """
    path = Path(path)
    aside = path.with_name(f"{path.name}.damaged-{time.strftime('%Y%m%d-%H%M%S')}")
    path.rename(aside)
    for suffix in ("-wal", "-shm"):  # the journal belongs to the damaged file now
        journal = path.with_name(path.name + suffix)
        if journal.exists():
            journal.rename(aside.with_name(aside.name + suffix))
    kept: dict[str, int] = {}
    lost: dict[str, int] = {}
    with contextlib.closing(sqlite3.connect(path, isolation_level=None)) as new:
        new.execute("BEGIN")
        for migration in MIGRATIONS:
            for statement in migration:
                new.execute(statement)
        new.execute(f"PRAGMA user_version={VERSION}")
        if aside.stat().st_size:
            with contextlib.closing(_open_readonly(aside)) as old:
                for table, columns in tables().items():
                    rows, missed = _salvage(old, table, columns)
                    marks = ", ".join("?" * len(columns))
                    for row in rows:
                        with contextlib.suppress(sqlite3.DatabaseError):
                            new.execute(
                                f"INSERT OR IGNORE INTO {table} ({', '.join(columns)}) "
                                f"VALUES ({marks})",
                                row,
                            )
                    kept[table], lost[table] = len(rows), missed
        new.execute("COMMIT")
    return Repair(path, aside, kept, lost)


def _salvage(
    db: sqlite3.Connection, table: str, columns: tuple[str, ...]
) -> tuple[list[tuple[object, ...]], int]:
    """The readable rows of a table, and how many rows could not be read."""
    wanted = ", ".join(columns)
    try:
        return list(db.execute(f"SELECT {wanted} FROM {table}")), 0
    except sqlite3.OperationalError:
        return [], 0  # the table (or a column) is not there: nothing to read
    except sqlite3.DatabaseError:
        pass  # a malformed page: read around it, row by row
    rows: list[tuple[object, ...]] = []
    missed = 0
    try:
        low, high = db.execute(f"SELECT min(rowid), max(rowid) FROM {table}").fetchone()
    except sqlite3.DatabaseError:
        low, high = 1, 100_000
    for rowid in range(int(low or 1), int(high or 0) + 1):
        try:
            row = db.execute(f"SELECT {wanted} FROM {table} WHERE rowid = ?", (rowid,)).fetchone()
        except sqlite3.DatabaseError:
            missed += 1
            continue
        if row is not None:
            rows.append(row)
    return rows, missed
