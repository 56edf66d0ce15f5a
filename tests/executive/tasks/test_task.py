"""The task model: phases and end causes."""

from __future__ import annotations

from executive.tasks.task import TaskEnd, TaskPhase


def test_a_task_ends_in_the_phase_its_end_cause_gives() -> None:
    cancelled = {TaskEnd.REQUESTER, TaskEnd.USER, TaskEnd.SHUTDOWN, TaskEnd.BEHAVIOR_CANCELLED}
    for end in TaskEnd:
        expected = (
            TaskPhase.SUCCEEDED
            if end is TaskEnd.SUCCEEDED
            else TaskPhase.CANCELLED
            if end in cancelled
            else TaskPhase.FAILED
        )
        assert end.phase is expected, end
