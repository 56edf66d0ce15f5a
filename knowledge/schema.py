"""The knowledge base schema as an ordered list of migrations.

``PRAGMA user_version`` holds how many migrations a database has had; opening a
database applies the missing ones in one transaction. Never edit a released
migration: append a new one.
"""

from __future__ import annotations


def _statements(script: str) -> tuple[str, ...]:
    """Split a script of plain DDL (no ';' inside statements) into statements."""
    return tuple(s.strip() for s in script.split(";") if s.strip())


MIGRATIONS: tuple[tuple[str, ...], ...] = (
    # 1: the tables of thesis 5.1-5.3
    _statements("""
    CREATE TABLE goals (
        id INTEGER PRIMARY KEY AUTOINCREMENT,
        expression TEXT NOT NULL,
        state TEXT NOT NULL,
        priority INTEGER NOT NULL DEFAULT 0,
        deadline REAL,
        source TEXT NOT NULL DEFAULT 'user',
        reason TEXT NOT NULL DEFAULT '',
        created REAL NOT NULL,
        updated REAL NOT NULL
    );
    CREATE INDEX goals_state ON goals(state);
    CREATE TABLE plans (
        id INTEGER PRIMARY KEY AUTOINCREMENT,
        state TEXT NOT NULL,
        engine TEXT NOT NULL DEFAULT '',
        goal_ids TEXT NOT NULL DEFAULT '[]',
        reason TEXT NOT NULL DEFAULT '',
        created REAL NOT NULL,
        updated REAL NOT NULL
    );
    CREATE TABLE plan_steps (
        plan_id INTEGER NOT NULL REFERENCES plans(id) ON DELETE CASCADE,
        idx INTEGER NOT NULL,
        action TEXT NOT NULL,
        args TEXT NOT NULL,
        start REAL NOT NULL,
        duration REAL,
        PRIMARY KEY (plan_id, idx)
    );
    CREATE TABLE tasks (
        id INTEGER PRIMARY KEY AUTOINCREMENT,
        action TEXT NOT NULL,
        behavior TEXT NOT NULL,
        args TEXT NOT NULL DEFAULT '{}',
        state TEXT NOT NULL,
        plan_id INTEGER REFERENCES plans(id),
        step INTEGER,
        result TEXT,
        reason TEXT NOT NULL DEFAULT '',
        created REAL NOT NULL,
        updated REAL NOT NULL
    );
    CREATE INDEX tasks_state ON tasks(state);
    CREATE TABLE objects (
        name TEXT PRIMARY KEY,
        type TEXT NOT NULL
    );
    CREATE TABLE facts (
        name TEXT NOT NULL,
        args TEXT NOT NULL,
        value TEXT NOT NULL,
        PRIMARY KEY (name, args)
    );
    CREATE TABLE components (
        name TEXT PRIMARY KEY,
        rating REAL NOT NULL,
        fault_count INTEGER NOT NULL DEFAULT 0,
        permanent_fault INTEGER NOT NULL DEFAULT 0,
        reason TEXT NOT NULL DEFAULT '',
        updated REAL NOT NULL
    );
    CREATE TABLE achievements (
        component TEXT NOT NULL,
        key TEXT NOT NULL,
        value TEXT NOT NULL,
        updated REAL NOT NULL,
        PRIMARY KEY (component, key)
    );
    CREATE TABLE return_values (
        id INTEGER PRIMARY KEY AUTOINCREMENT,
        task_id INTEGER REFERENCES tasks(id),
        component TEXT NOT NULL,
        value TEXT NOT NULL,
        stamp REAL NOT NULL
    );
    CREATE TABLE parameters (
        component TEXT NOT NULL,
        key TEXT NOT NULL,
        value TEXT NOT NULL,
        updated REAL NOT NULL,
        PRIMARY KEY (component, key)
    );
    CREATE TABLE events (
        id INTEGER PRIMARY KEY AUTOINCREMENT,
        stamp REAL NOT NULL,
        kind TEXT NOT NULL,
        subject TEXT NOT NULL DEFAULT '',
        data TEXT NOT NULL DEFAULT '{}'
    );
    CREATE INDEX events_kind ON events(kind);
    """),
    # 2: maintenance goals, re-posted whenever they stop holding
    _statements("""
    ALTER TABLE goals ADD COLUMN keep INTEGER NOT NULL DEFAULT 0
    """),
    # 3: what happened to each step of a plan (written by the plan executor)
    ("ALTER TABLE plan_steps ADD COLUMN state TEXT NOT NULL DEFAULT 'pending'",),
    # 4: facts that take effect later ("the door opens at 14:00"), a wall-clock time each
    _statements("""
    CREATE TABLE timed_facts (
        name TEXT NOT NULL,
        args TEXT NOT NULL,
        value TEXT NOT NULL,
        at REAL NOT NULL,
        PRIMARY KEY (name, args, at)
    );
    CREATE INDEX timed_facts_at ON timed_facts(at)
    """),
    # 5: what is asked on every change of facts, or per goal, reads no more than it needs
    # (a robot's history grows with every goal it takes)
    _statements("""
    CREATE INDEX goals_kept ON goals(keep, state);
    CREATE INDEX events_subject ON events(subject)
    """),
)

VERSION = len(MIGRATIONS)
