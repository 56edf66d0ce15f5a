"""The task ledger keeps the newest ended tasks in memory, the knowledge base all of them."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from executive.tasks import ledger
from executive.tasks.ledger import TaskLedger
from executive.tasks.task import Task, TaskPhase
from knowledge.knowledge_base import KnowledgeBase


def task(number: int) -> Task:
    return Task(str(number), "move_to", "move_to", {}, 1.0, 0.0, None, (), None)


def test_ended_tasks_are_bounded_and_running_ones_kept(tmp_path: Path, monkeypatch: Any) -> None:
    monkeypatch.setattr(ledger, "KEPT_ENDED", 5)
    with KnowledgeBase(tmp_path / "kb.db") as kb:
        tasks = TaskLedger(kb, control=None)  # type: ignore[arg-type]
        running = task(0)
        tasks.add(running)
        tasks.set_phase(running, TaskPhase.RUNNING)
        for number in range(1, 21):
            ended = task(number)
            tasks.add(ended)
            tasks.set_phase(ended, TaskPhase.SUCCEEDED)
        assert [t.id for t in tasks] == ["0", "16", "17", "18", "19", "20"]
        assert len(kb.events(kind="TASK_REQUESTED")) == 21
