"""A damaged knowledge base is refused at start with one line, checked, and repaired
without losing what can still be read."""

from __future__ import annotations

import sqlite3
from collections.abc import Callable
from pathlib import Path

import pytest

from knowledge.errors import KnowledgeError
from knowledge.health import check, repair
from knowledge.knowledge_base import KnowledgeBase
from knowledge.records import GoalState
from tests.conftest import USECASE, run_dura

GOALS = 300  # enough rows that the goals table spans many pages


def written(path: Path) -> Path:
    """A knowledge base with goals, a fault and events, closed cleanly."""
    with KnowledgeBase(path) as kb:
        for n in range(GOALS):
            kb.add_goal(f"(picture_taken place{n})", priority=n % 5)
        kb.register_component("lidar", 1.0)
        kb.record_fault("lidar", "crashed", max_faults=3)
        kb.log_event("TEST", "written")
    db = sqlite3.connect(path)
    db.execute("PRAGMA wal_checkpoint(TRUNCATE)")
    db.close()
    return path


def emptied(path: Path) -> None:
    path.write_bytes(b"")


def missing_table(path: Path) -> None:
    db = sqlite3.connect(path)
    db.execute("DROP TABLE plan_steps")
    db.commit()
    db.close()


def malformed_page(path: Path) -> None:
    """Overwrite one page in the middle of the goals' pages with garbage."""
    size = path.stat().st_size
    page = 4096
    with path.open("r+b") as f:
        f.seek((size // page // 2) * page)
        f.write(b"\xde\xad\xbe\xef" * (page // 4))


DAMAGE: dict[str, Callable[[Path], None]] = {
    "emptied": emptied,
    "missing table": missing_table,
    "malformed page": malformed_page,
}


@pytest.mark.parametrize("damage", list(DAMAGE), ids=list(DAMAGE))
def test_a_damaged_knowledge_base_is_refused_with_one_line_naming_it(
    tmp_path: Path, damage: str
) -> None:
    path = written(tmp_path / "robot.db")
    DAMAGE[damage](path)
    before = path.read_bytes()
    with pytest.raises(KnowledgeError) as raised:
        KnowledgeBase(path)
    assert str(raised.value).startswith(f"{path}: ")
    assert "\n" not in str(raised.value)
    assert path.read_bytes() == before  # nothing changed, nothing started afresh
    assert not check(path).sound


def test_dura_run_refuses_a_damaged_knowledge_base_and_exits_1(tmp_path: Path) -> None:
    path = written(tmp_path / "usecase.db")
    emptied(path)
    done = run_dura(
        "run", str(USECASE), "--db", str(path), "--endpoint", "tcp/127.0.0.1:0", cwd=tmp_path
    )
    assert done.returncode == 1
    assert done.stderr.strip().splitlines() == [done.stderr.strip()]
    assert f"{path}: the file is empty (0 bytes)" in done.stderr
    assert "Traceback" not in done.stderr
    assert path.stat().st_size == 0


def test_kb_check_says_what_is_wrong_and_exits_1(tmp_path: Path) -> None:
    path = written(tmp_path / "robot.db")
    assert run_dura("kb", "check", "--db", str(path)).returncode == 0
    missing_table(path)
    done = run_dura("kb", "check", "--db", str(path))
    assert done.returncode == 1
    assert f"{path}: missing tables: plan_steps" in done.stderr


@pytest.mark.parametrize("damage", list(DAMAGE), ids=list(DAMAGE))
def test_a_repair_keeps_every_row_that_can_be_read(tmp_path: Path, damage: str) -> None:
    path = written(tmp_path / "robot.db")
    DAMAGE[damage](path)
    done = repair(path)
    assert done.kept_aside.exists()  # the damaged file is never deleted
    assert check(path).sound
    with KnowledgeBase(path) as kb:
        goals = kb.goals()
        if damage == "emptied":
            assert goals == []
        elif damage == "missing table":
            assert len(goals) == GOALS  # everything but the dropped table
            assert kb.component("lidar").fault_count == 1
        else:
            assert 0 < len(goals) <= GOALS
            assert len(goals) + done.lost["goals"] >= GOALS - 20  # only the bad page's rows
        assert all(g.state is GoalState.PENDING for g in goals)


def test_kb_repair_through_the_command_line(tmp_path: Path) -> None:
    path = written(tmp_path / "robot.db")
    missing_table(path)
    done = run_dura("kb", "repair", "--db", str(path))
    assert done.returncode == 0, done.stderr
    assert done.stdout.startswith(f"{path}: repaired: kept ")
    assert run_dura("kb", "check", "--db", str(path)).returncode == 0
    with KnowledgeBase(path) as kb:
        assert len(kb.goals()) == GOALS
