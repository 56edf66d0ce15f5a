"""Crash recovery end to end: a real ``dura run`` of the use case killed (SIGKILL)
while its steps run, across replans, and started again on the same knowledge base.

The facts after each kill and each restart are checked against a replay of the event
log (:mod:`tests.e2e.kill_rounds`): each fact is what the finished steps made it, and a
step the dead executive left under way is taken back exactly once.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import pytest

from executive.testing.harness import RobotProcess
from tests.conftest import USECASE, wait_for
from tests.e2e.kill_rounds import KillRounds, check, initial_facts

pytestmark = pytest.mark.slow

Start = Callable[..., RobotProcess]
ROUNDS = 12  # tests/benchmarks/recovery.py kills 200 times
FORCED = 5  # rounds at most that replan and kill mid-step, if the random ones did not


def test_a_kill_while_the_replanned_drive_runs_leaves_the_robot_in_one_place(
    dura_robot: Start,
) -> None:
    """The issue's case: a picture of the lab, then the office; SIGKILL while a
    ``move_to`` of the second plan runs; restart; where is the robot?"""
    robot = dura_robot(USECASE, changes={"behaviors": {"move_to": {"params": {"duration": 2.0}}}})
    initial = initial_facts(robot.description)
    robot.submit_goal("(picture_taken lab)")
    assert wait_for(lambda: bool(robot.events("START")), 60)
    robot.submit_goal("(robot_at office)")

    def second_plan_drives() -> bool:
        events = robot.events()
        starts = [e.id for e in events if e.kind == "PLAN_START"]
        return len(starts) >= 2 and any(
            e.kind in ("START", "ADOPT") and e.subject.startswith("move_to")
            and e.id > starts[1] and not any(
                later.kind in ("END", "FAIL", "CANCEL") and later.subject == e.subject
                and later.id > e.id for later in events
            )
            for e in events
        )  # fmt: skip

    assert wait_for(second_plan_drives, 90)
    robot.kill()
    robot.start()

    assert len(robot.facts("robot_at")) == 1, robot.facts("robot_at")
    assert check(initial, robot.kb_path, restarted=True) == []


def test_the_facts_are_exact_after_kills_at_random_moments_across_replans(
    tmp_path: Path,
) -> None:
    rounds = KillRounds(tmp_path, seed=15)
    try:
        for _ in range(ROUNDS):
            rounds.round()
        for _ in range(FORCED):  # random moments on a loaded machine may miss the case
            if any(r.replanned_mid_step for r in rounds.rounds):
                break
            rounds.round(replan=True)
        final = rounds.final_check()
    finally:
        rounds.close()
    wrong = [r for r in rounds.rounds if r.problems]
    mid_step = [r for r in rounds.rounds if r.running]
    replanned = [r for r in mid_step if r.replanned_mid_step]
    print(
        f"facts correct after {len(rounds.rounds) - len(wrong)} of {len(rounds.rounds)} kills "
        f"({len(mid_step)} while a step ran, {len(replanned)} of them after a replan)"
    )
    assert wrong == [], "\n".join(f"round {r.number} ({r.did}): {r.problems}" for r in wrong)
    assert final == []
    assert replanned, "no kill came while a step of a replanned plan ran: nothing was tested"
