"""The task executor and the launcher in a process of their own (``dura run --only
tasks``) beside an executive that runs without them: the high level plans in the
executive, and the tasks process starts the components and carries out the steps."""

from __future__ import annotations

import contextlib
import json
import os
import signal
from collections.abc import Iterator
from pathlib import Path

import psutil
import pytest

from executive.bus.api.components import COMPONENT_LIST
from executive.bus.keys import service_alive
from executive.testing.harness import RobotProcess, ServiceGroupProcess, robot_variant
from tests.conftest import USECASE, nobody_answers, run_dura, wait_for

pytestmark = pytest.mark.slow

FAST = 10.0  # robot time ten times faster than the wall clock
WITHOUT_TASKS = ["--without", "tasks"]


@contextlib.contextmanager
def split(description: Path, folder: Path) -> Iterator[tuple[RobotProcess, ServiceGroupProcess]]:
    """The executive without the task executor, and the tasks process beside it."""
    with (
        RobotProcess(description, folder, run_args=WITHOUT_TASKS, time_scale=FAST) as robot,
        ServiceGroupProcess(robot, "tasks") as tasks,
    ):
        yield robot, tasks


def living(pids: list[int]) -> list[int]:
    """Those of ``pids`` that still run (a zombie waiting for its reaper does not)."""
    alive = []
    for pid in pids:
        with contextlib.suppress(psutil.NoSuchProcess):
            if psutil.Process(pid).status() != psutil.STATUS_ZOMBIE:
                alive.append(pid)
    return alive


def test_the_tasks_process_starts_the_components_and_runs_the_steps(tmp_path: Path) -> None:
    # a move takes 20 robot seconds (2 s of wall time): time to look at what runs
    changes = {"behaviors": {"move_to": {"params": {"duration": 20.0}}}}
    description = robot_variant(USECASE, tmp_path / "description", changes)
    with RobotProcess(description, tmp_path, run_args=WITHOUT_TASKS, time_scale=FAST) as robot:
        env = robot.environment()
        assert nobody_answers(robot.bus, COMPONENT_LIST)  # nobody launches yet
        with ServiceGroupProcess(robot, "tasks") as tasks:
            assert robot.bus.alive(service_alive("tasks"))
            goal = robot.submit_goal("(picture_taken lab)")
            robot.wait_for_event("TASK_STARTED", "move_to", timeout=60)
            listed = run_dura("component", "list", "--json", cwd=tmp_path, env=env)
            assert listed.returncode == 0, listed.stderr
            running = [c for c in json.loads(listed.stdout)["components"] if c.get("pid")]
            assert {c["component"] for c in running} >= {"robot_base", "move_to"}
            for component in running:  # children of the tasks process, not the executive's
                parents = {p.pid for p in psutil.Process(component["pid"]).parents()}
                assert tasks.pid in parents and robot.pid not in parents
            status = run_dura("status", "--json", cwd=tmp_path, env=env)
            assert status.returncode == 0, status.stderr
            assert "move_to" in json.dumps(json.loads(status.stdout)["tasks"])
            robot.wait_for(goal, "achieved", timeout=90)
            assert robot.facts("picture_taken") == ["(picture_taken lab)"]
            succeeded = robot.events("TASK_SUCCEEDED")  # logged by the tasks process
            assert any("take_picture(lab)" in e.subject for e in succeeded)
            robot.wait_for_event("TASK_STARTED", "take_picture", timeout=10)
            pids = [c.pid for c in robot.components() if c.pid] + [c["pid"] for c in running]
        assert wait_for(lambda: living(pids) == [], 10), living(pids)
        # status still answers: what the task executor answered is an error now
        gone = run_dura("status", "--json", cwd=tmp_path, env=env)
        assert gone.returncode == 0, gone.stderr
        answer = json.loads(gone.stdout)
        assert "error" in answer["tasks"] and "error" in answer["components"], answer
    assert "tasks of robot 'usecase': runs" in (tmp_path / "tasks.log").read_text()


def test_a_second_tasks_process_on_the_same_knowledge_base_is_refused(tmp_path: Path) -> None:
    with split(USECASE, tmp_path) as (robot, _):
        argv = ["run", str(USECASE), "--only", "tasks", "--endpoint", robot.endpoint]
        second = run_dura(*argv, "--db", str(robot.kb_path), cwd=tmp_path, env=robot.environment())
        assert second.returncode != 0
        assert second.stderr.strip().splitlines() == [
            f"dura: {robot.kb_path}: the knowledge base is in use by another tasks process "
            f"(pid {second.stderr.split('(pid ')[1].split(')')[0]}); stop it first or give this "
            "one another --db"
        ]


def test_a_killed_tasks_process_leaves_nothing_running_and_its_successor_carries_on(
    tmp_path: Path,
) -> None:
    # a move takes 20 robot seconds (2 s of wall time): time to kill the process on the way
    changes = {"behaviors": {"move_to": {"params": {"duration": 20.0}}}}
    description = robot_variant(USECASE, tmp_path / "description", changes)
    with split(description, tmp_path) as (robot, tasks):
        goal = robot.submit_goal("(robot_at lab)")
        robot.wait_for_event("TASK_STARTED", "move_to", timeout=60)
        pids = [c.pid for c in robot.components() if c.pid]
        trees = pids + [c.pid for p in pids for c in psutil.Process(p).children(recursive=True)]
        os.kill(tasks.pid, signal.SIGKILL)
        assert wait_for(lambda: living(trees) == [], 10), living(trees)
        # the executive's plan learns that the step's task executor is gone
        failed = robot.wait_for_event("FAIL", "move_to", timeout=30)
        assert "the task executor is gone" in json.dumps(failed.data)
        tasks.stop()
        tasks.start()  # a new tasks process: the planner's next plan runs there
        robot.wait_for(goal, "achieved", timeout=120)
        assert robot.facts("robot_at") == ["(robot_at lab)"]


def test_a_fault_marked_in_the_tasks_process_blocks_the_executives_plans_until_reset(
    tmp_path: Path,
) -> None:
    with split(USECASE, tmp_path) as (robot, _):
        env = robot.environment()
        marked = run_dura("component", "fault", "take_picture", cwd=tmp_path, env=env)
        assert marked.returncode == 0, marked.stderr
        goal = robot.submit_goal("(picture_taken lab)")
        robot.wait_for(goal, "unreachable", timeout=60)
        assert "take_picture" in robot.goal(goal).reason
        reset = run_dura("component", "reset", "take_picture", cwd=tmp_path, env=env)
        assert reset.returncode == 0, reset.stderr
        # the reset is logged in the tasks process: the executive's goal planner follows it
        robot.wait_for(goal, "achieved", timeout=90)
