"""One executive per knowledge base, whatever path names it."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from executive.runtime.run_lock import RunLock
from executive.testing.harness import RobotProcess, free_endpoint
from knowledge.errors import KnowledgeError
from tests.conftest import USECASE, run_dura


def test_a_hard_link_to_a_locked_knowledge_base_is_the_same_file(tmp_path: Path) -> None:
    database = tmp_path / "kb.db"
    database.touch()
    (tmp_path / "other").mkdir()
    with RunLock(database):
        os.link(database, tmp_path / "other" / "kb.db")
        with pytest.raises(KnowledgeError, match="in use by another executive"):
            RunLock(tmp_path / "other" / "kb.db").acquire()
    with RunLock(tmp_path / "other" / "kb.db"):  # free again once the first ends
        pass


def test_a_symbolic_link_is_refused(tmp_path: Path) -> None:
    database = tmp_path / "kb.db"
    database.touch()
    (tmp_path / "link.db").symlink_to(database)
    with pytest.raises(KnowledgeError, match="is a symbolic link"):
        RunLock(tmp_path / "link.db").acquire()


def test_a_second_executive_is_refused_through_any_other_name(tmp_path: Path) -> None:
    with RobotProcess(USECASE, tmp_path) as robot:
        link = tmp_path / "link.db"
        link.symlink_to(robot.kb_path)
        hard = tmp_path / "hard.db"
        os.link(robot.kb_path, hard)
        for name, reason in ((link, "is a symbolic link"), (hard, "in use by another executive")):
            argv = ["run", str(USECASE), "--endpoint", free_endpoint(), "--db", str(name)]
            second = run_dura(*argv, cwd=tmp_path, env=robot.environment())
            assert second.returncode != 0
            lines = second.stderr.strip().splitlines()
            assert len(lines) == 1 and reason in lines[0], second.stderr
        assert robot.running
        assert robot.events("EXECUTIVE_STARTED")[1:] == []  # no second run was logged
