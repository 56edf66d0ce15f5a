"""``dura goal add --wait`` and ``dura goal watch``: following a goal until it ends.

One use-case robot (a real ``dura run``) serves the whole module; the goals follow each
other on it, so each test leaves the robot idle.
"""

from __future__ import annotations

import dataclasses
import io
import json
import re
import subprocess
from collections.abc import Iterator

import pytest

from executive.bus.api.planning import PlanReply
from executive.bus.reports import ExecutionStatus, StepStatus
from executive.cli.goal import GoalView, progress
from executive.testing.harness import RobotProcess
from knowledge.records import Goal, GoalState, Plan, PlanState, PlanStep
from tests.conftest import ROOT, USECASE, run_dura

GOAL = Goal(3, "(picture_taken lab)", GoalState.EXECUTING, created=100.0, updated=101.0)
PLAN = Plan(
    2,
    PlanState.EXECUTING,
    tuple(PlanStep(i, "move_to", (), 0.0) for i in range(3)),
    goal_ids=(3,),
)


@pytest.fixture(scope="module")
def robot(tmp_path_factory: pytest.TempPathFactory) -> Iterator[RobotProcess]:
    with pytest.MonkeyPatch.context() as patch:
        patch.setenv("PYTHONPATH", str(ROOT))  # the components import the examples
        with RobotProcess(USECASE, tmp_path_factory.mktemp("goals")) as running:
            yield running


def dura(robot: RobotProcess, *args: str) -> subprocess.CompletedProcess[str]:
    """The dura command, run in the robot's folder (it finds the executive there)."""
    return run_dura(*args, cwd=robot.folder)


# --- how a followed goal is shown ------------------------------------------------------


def test_the_progress_line_says_the_state_the_time_and_the_steps_under_way() -> None:
    execution = ExecutionStatus(
        plan=2,
        steps=(
            StepStatus(0, "move_to(dock, lab)", "ended"),
            StepStatus(1, "take_picture(lab)", "running"),
        ),
    )
    line = progress(GOAL, PlanReply(PLAN, execution), now=104.5)
    assert line == (
        "goal 3 (picture_taken lab): executing 4.5 s; plan 2: 1 of 3 steps ended, "
        "take_picture(lab) running"
    )


def test_the_progress_line_leaves_out_a_plan_that_does_not_pursue_the_goal() -> None:
    other = dataclasses.replace(PLAN, goal_ids=(7,))
    assert progress(GOAL, PlanReply(other, ExecutionStatus(plan=2)), now=101.0) == (
        "goal 3 (picture_taken lab): executing 1.0 s"
    )
    waits = progress(GOAL, PlanReply(PLAN, ExecutionStatus(plan=1)), now=101.0)
    assert waits.endswith("; plan 2 waits")
    assert progress(GOAL, None, now=99.0) == "goal 3 (picture_taken lab): executing 0.0 s"


def test_on_a_terminal_one_line_is_redrawn_and_taken_away_at_the_end() -> None:
    out = io.StringIO()
    view = GoalView(out, live=True, changes=False)
    view.show(GOAL, None, now=101.0)
    view.show(dataclasses.replace(GOAL, state=GoalState.ACHIEVED), None, now=102.0)
    view.close()
    text = out.getvalue()
    assert text.count("\r") == 3 and "\n" not in text
    assert text.endswith("\r\x1b[K")


def test_elsewhere_each_change_of_state_is_a_line_of_its_own() -> None:
    out = io.StringIO()
    view = GoalView(out, live=False, changes=True)
    for state in ("pending", "pending", "executing", "failed"):
        reason = "no plan" if state == "failed" else ""
        view.show(dataclasses.replace(GOAL, state=GoalState(state), reason=reason), None, now=101.0)
    view.close()
    lines = out.getvalue().splitlines()
    assert [line.split("  ", 1)[1] for line in lines] == [
        "goal 3 pending",
        "goal 3 executing",
        "goal 3 failed: no plan",
    ]


# --- on a running robot ----------------------------------------------------------------


def test_a_goal_added_with_wait_exits_0_once_achieved(robot: RobotProcess) -> None:
    done = dura(robot, "goal", "add", "(picture_taken lab)", "--wait")
    assert done.returncode == 0, done.stderr
    lines = done.stdout.splitlines()
    added = re.fullmatch(r"goal (\d+): \(picture_taken lab\) \(pending\)", lines[0])
    assert added is not None
    goal_id = int(added.group(1))
    assert re.fullmatch(rf"goal {goal_id} \(picture_taken lab\): achieved in \d+\.\d s", lines[-1])
    assert "\r" not in done.stdout  # not a terminal: no live line
    assert robot.goal(goal_id).state is GoalState.ACHIEVED


def test_with_json_only_the_ended_goal_is_printed(robot: RobotProcess) -> None:
    done = dura(robot, "goal", "add", "(robot_at office)", "--wait", "--json")
    assert done.returncode == 0, done.stderr
    goal = json.loads(done.stdout)  # one JSON document, nothing else
    assert (goal["expression"], goal["state"]) == ("(robot_at office)", "achieved")


def test_an_unreachable_goal_exits_1_with_the_reason(robot: RobotProcess) -> None:
    done = dura(robot, "goal", "add", "(connected lab lab)", "--wait")
    assert done.returncode == 1
    last = done.stderr.strip().splitlines()[-1]
    assert last.startswith("dura: goal ") and "(connected lab lab): unreachable: " in last
    assert len(last) > len("dura: goal 9 (connected lab lab): unreachable: ")


def test_watch_follows_a_goal_of_another_command_to_its_end(robot: RobotProcess) -> None:
    goal_id = robot.submit_goal("(picture_taken office)")
    watched = dura(robot, "goal", "watch", str(goal_id))
    assert watched.returncode == 0, watched.stderr
    assert watched.stdout.splitlines()[-1].startswith(f"goal {goal_id} (picture_taken office)")
    again = dura(robot, "goal", "watch", str(goal_id), "--json")  # ended already: at once
    assert again.returncode == 0 and json.loads(again.stdout)["state"] == "achieved"


def test_waiting_gives_up_after_the_timeout_and_leaves_the_goal_alone(
    robot: RobotProcess,
) -> None:
    goal_id = robot.submit_goal("(robot_at dock)")
    try:
        waited = dura(robot, "goal", "watch", str(goal_id), "--timeout", "0.5")
        assert waited.returncode == 1
        assert f"goal {goal_id} (robot_at dock): still " in waited.stderr
        assert robot.goal(goal_id).state.is_open
    finally:
        robot.wait_for(goal_id)


def test_watching_a_goal_that_does_not_exist_says_so(robot: RobotProcess) -> None:
    done = dura(robot, "goal", "watch", "999")
    assert (done.returncode, done.stderr.strip()) == (1, "dura: no goal 999")


def test_a_cancelled_goal_ends_the_wait_with_exit_1(robot: RobotProcess) -> None:
    goal_id = robot.submit_goal("(robot_at lab)")  # the robot is at the dock: seconds away
    robot.cancel_goal(goal_id)
    done = dura(robot, "goal", "watch", str(goal_id))
    assert done.returncode == 1
    assert f"dura: goal {goal_id} (robot_at lab): cancelled" in done.stderr
