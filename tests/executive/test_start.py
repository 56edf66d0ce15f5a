"""How the executive starts: its bus API answers first, unified-planning loads only in
the planner worker (in the background), and a domain that does not fit the robot ends
``dura run`` with the reason."""

from __future__ import annotations

import contextlib
import os
import signal
import subprocess
import sys
import textwrap
import time
from collections.abc import Iterator
from pathlib import Path

import pytest

from executive.bus import security
from executive.bus.api import planning
from executive.bus.session import Bus
from executive.testing.harness import free_endpoint, robot_variant
from knowledge.errors import BusError
from knowledge.records import GoalState
from tests.conftest import ROOT, USECASE

pytestmark = pytest.mark.slow


def dura_run(description: Path, folder: Path, endpoint: str) -> subprocess.Popen[str]:
    return subprocess.Popen(
        [sys.executable, "-m", "executive.cli", "run", str(description),
         "--endpoint", endpoint, "--db", str(folder / "robot.db")],
        cwd=folder, env={**os.environ, "PYTHONPATH": str(ROOT)},
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
    )  # fmt: skip


@pytest.fixture
def running(tmp_path: Path) -> Iterator[tuple[subprocess.Popen[str], Path, str]]:
    endpoint = free_endpoint()
    process = dura_run(USECASE, tmp_path, endpoint)
    try:
        yield process, tmp_path, endpoint
    finally:
        process.send_signal(signal.SIGTERM)
        process.communicate(timeout=30)


def connect(folder: Path, endpoint: str, timeout: float = 60.0) -> Bus:
    """A bus session to the executive as soon as it listens."""
    deadline = time.monotonic() + timeout
    while True:
        try:
            login = security.find_login("usecase", security.OPERATOR, [folder])
            return Bus("usecase", name="test", endpoint=endpoint, login=login)
        except BusError:
            if time.monotonic() > deadline:
                raise
            time.sleep(0.02)


def test_a_goal_sent_as_soon_as_the_executive_answers_waits_for_the_planner(
    running: tuple[subprocess.Popen[str], Path, str],
) -> None:
    _process, folder, endpoint = running
    with connect(folder, endpoint) as bus:
        first = None
        while first is None:  # the bus may listen a moment before the API answers
            with contextlib.suppress(BusError):
                first = planning.STATUS.call(bus, timeout=1.0)
        assert first.robot == "usecase"
        facts = planning.STATE_GET.call(bus, planning.StateQuery("robot_at")).facts
        assert [f.text for f in facts] == ["(robot_at dock)"]  # a new robot waits for it
        goal = planning.GOAL_ADD.call(bus, planning.GoalAdd("(robot_at dock)")).goal
        assert goal.state is GoalState.PENDING  # accepted: the planner had parsed the domain
        deadline = time.monotonic() + 60
        shown = planning.GoalId(goal.id)
        while planning.GOAL_SHOW.call(bus, shown).goal.state is not GoalState.ACHIEVED:
            assert time.monotonic() < deadline, "the goal was not achieved"
            time.sleep(0.05)
        status = planning.STATUS.call(bus)
        assert status.planning is not None and status.planning.starting is False


def test_the_executive_process_leaves_unified_planning_to_its_planner_worker(
    tmp_path: Path,
) -> None:
    script = textwrap.dedent(f"""
        import sys
        from pathlib import Path
        from executive.bus.service import ServiceState
        from executive.executive import Executive
        from knowledge.robot import load_robot

        robot = load_robot(Path({str(USECASE)!r}), domain=False)
        folder = Path({str(tmp_path)!r})
        with Executive(robot, endpoint={free_endpoint()!r}, kb_path=folder / "robot.db",
                       folder=folder) as executive:
            assert executive.high_level.wait_for(ServiceState.ACTIVE, 60)
            print("unified_planning" in sys.modules, len(executive.kb.facts()) > 0)
    """)
    done = subprocess.run(
        [sys.executable, "-c", script], capture_output=True, text=True, timeout=120,
        cwd=tmp_path, env={**os.environ, "PYTHONPATH": str(ROOT)}, check=False,
    )  # fmt: skip
    assert done.returncode == 0, done.stderr
    assert done.stdout.split() == ["False", "True"]


def test_a_domain_that_does_not_fit_the_robot_ends_dura_run_with_the_reason(
    tmp_path: Path,
) -> None:
    variant = robot_variant(
        USECASE, tmp_path / "robot", {"tasks": {"fly": {"behavior": "move_to", "goal": {}}}}
    )
    process = dura_run(variant, tmp_path, free_endpoint())
    try:
        out, err = process.communicate(timeout=120)
    finally:
        if process.poll() is None:
            process.kill()
            process.communicate()
    assert process.returncode == 1
    (line,) = err.strip().splitlines()
    assert line.startswith(f"dura: {variant}:")
    assert "task 'fly' names no action of domain 'usecase'" in line
    assert "runs on" in out  # it had answered on the bus meanwhile
