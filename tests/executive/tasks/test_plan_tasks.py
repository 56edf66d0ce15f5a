"""Plan steps as tasks: a step the plan cancels reports nothing more, a step whose task
someone else ends fails (and the planner plans again)."""

from __future__ import annotations

import threading
from pathlib import Path
from typing import Any

import pytest

from executive.bus.api.tasks import TASK_STOP, TaskId
from executive.bus.reports import ExecutorTask
from executive.planning.partial_order import Step
from executive.planning.task_runner import Progress, StepReport
from executive.tasks.executor import TaskExecutor
from executive.tasks.plan_tasks import PlanTasks
from executive.tasks.task import TaskEnd
from tests.conftest import wait_for
from tests.executive.tasks.executor_rig import executor, slow_camera_robot

pytestmark = pytest.mark.slow


class Reports:
    """What the runner reported, per step."""

    def __init__(self) -> None:
        self._lock = threading.Lock()
        self._seen: dict[int, list[tuple[Progress, Any]]] = {}

    def report(self, step: int) -> StepReport:
        def post(_: StepReport, kind: Progress, value: Any) -> None:
            with self._lock:
                self._seen.setdefault(step, []).append((kind, value))

        return StepReport(post)

    def of(self, step: int) -> list[tuple[Progress, Any]]:
        with self._lock:
            return list(self._seen.get(step, []))


def task_of(tasks: TaskExecutor, name: str) -> ExecutorTask:
    return next(t for t in tasks.tasks() if t.name == name)


def picture(index: int, place: str) -> Step:
    return Step(index, "take_picture", (place,), ("p",), start=0.0, duration=5.0)


def test_a_step_its_plan_cancels_reports_nothing_and_one_a_user_stops_fails(
    endpoint: str, tmp_path: Path
) -> None:
    robot = slow_camera_robot(delay=0.5, picture=5.0)
    with executor(robot, endpoint, tmp_path) as (tasks, r):
        plan = r.kb.store_plan([]).id
        reports, runner = Reports(), PlanTasks(tasks, robot)
        dropped = runner.run(picture(0, "lab"), plan, reports.report(0))
        runner.run(picture(1, "office"), plan, reports.report(1))  # waits for the first
        dropped.cancel()
        TASK_STOP.call(r.bus, TaskId(task_of(tasks, "take_picture(office)").id))
        assert wait_for(lambda: reports.of(1) != [], 30)
        assert reports.of(1)[-1] == (Progress.FAILED, "cancelled: stopped by the user")
        assert wait_for(lambda: task_of(tasks, "take_picture(lab)").state == "cancelled", 30)
        assert task_of(tasks, "take_picture(lab)").ended_by == TaskEnd.REQUESTER.value
        assert all(kind is not Progress.FAILED for kind, _ in reports.of(0)), reports.of(0)
