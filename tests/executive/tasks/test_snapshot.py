"""What the status queries show, from a snapshot of task views (no worker involved)."""

from __future__ import annotations

from executive.tasks.snapshot import Snapshot
from executive.tasks.task import TaskEnd, TaskPhase, TaskView

NOW = 1000.0
CAM = {"camera": "cam"}


def test_the_schedule_shows_open_tasks_in_seconds_from_now_and_leaves_ended_ones_out() -> None:
    snapshot = Snapshot(
        (
            TaskView("1", "take_picture", 4.0, phase=TaskPhase.RUNNING, providers=CAM,
                     began=NOW - 3.0),
            TaskView("2", "take_picture", 2.0, start_at=NOW + 5.0),
            TaskView("3", "take_picture", 2.0, phase=TaskPhase.SUCCEEDED, end=TaskEnd.SUCCEEDED),
        ),
        running=frozenset({"cam"}),
        faulty=frozenset({"lidar"}),
    )  # fmt: skip
    shown = snapshot.schedule(NOW)
    assert [(r.id, r.start, r.end) for r in shown.tasks] == [
        ("1", -3.0, 1.0),
        ("2", 5.0, 7.0),
    ]
    assert (shown.running, shown.faulty) == (["cam"], ["lidar"])
    listed = snapshot.task_list()
    assert [(t.id, t.state, t.ended_by) for t in listed] == [
        ("1", "running", None),
        ("2", "waiting", None),
        ("3", "succeeded", "succeeded"),
    ]
    assert listed[0].functionalities == ("cam",)


def test_a_task_asked_for_joins_the_snapshot_as_waiting() -> None:
    snapshot = Snapshot().adding(TaskView("7", "move_to", 5.0, name="move_to(dock, lab)"))
    assert [(t.id, t.name, t.state) for t in snapshot.task_list()] == [
        ("7", "move_to(dock, lab)", "waiting")
    ]


def test_a_task_waiting_behind_a_running_one_is_drawn_after_it_as_the_scheduler_decided() -> None:
    snapshot = Snapshot(
        (
            TaskView("1", "move_to", 5.0, phase=TaskPhase.RUNNING, providers=CAM, began=NOW - 1.0),
            TaskView("2", "move_to", 5.0, behind=("1",)),
        )
    )
    assert [(r.id, r.start, r.end) for r in snapshot.schedule(NOW).tasks] == [
        ("1", -1.0, 4.0),
        ("2", 4.0, 9.0),
    ]
    overran = snapshot.schedule(NOW + 6.0)  # the first runs longer than planned
    assert [(r.id, r.start) for r in overran.tasks] == [("1", -7.0), ("2", 0.0)]
