"""When the high level plans again, end to end: a real executive (robot r1 of the fleet
example, on its own), its real components on simulated hardware, a real planner. A goal
achieved leaves the running plan to the others, while the battery's readings change the
robot's facts all along; a round's reason is what changed, never a reading."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import pytest

from executive.testing.harness import RobotProcess

pytestmark = pytest.mark.slow

R1 = Path(__file__).parents[2] / "examples" / "fleet" / "r1.yaml"
Start = Callable[..., RobotProcess]
SCALE = 2.0  # robot time twice as fast as the wall clock: a drive takes 2.5 s

# r1's own world (the fleet example gives it none: the fleet plans for it)
WORLD = """(define (problem r1-alone) (:domain transport_robot)
  (:objects dock1 store lab office - place parcel1 parcel2 - crate)
  (:init (robot_at dock1) (hands_free) (= (battery_level) 100)
    (road dock1 store) (road store dock1) (road store lab) (road lab store)
    (road store office) (road office store)
    (crate_at parcel1 store) (crate_at parcel2 store))
  (:goal (and)))
"""


def test_a_delivered_goal_leaves_the_plan_to_the_other_and_readings_replan_nothing(
    dura_robot: Start, tmp_path: Path
) -> None:
    problem = tmp_path / "r1-alone.pddl"
    problem.write_text(WORLD, encoding="utf-8")
    robot = dura_robot(R1, changes={"problem": str(problem)}, time_scale=SCALE)
    lab = robot.submit_goal("(crate_at parcel1 lab)")
    office = robot.submit_goal("(crate_at parcel2 office)")
    robot.wait_for(lab, "achieved", timeout=120)
    robot.wait_for(office, "achieved", timeout=120)

    events = robot.events()
    kinds = [(e.kind, e.subject) for e in events]
    first_done = min(kinds.index(("GOAL_ACHIEVED", f"goal {g}")) for g in (lab, office))
    last_done = max(kinds.index(("GOAL_ACHIEVED", f"goal {g}")) for g in (lab, office))
    readings = [
        e for e in events[first_done:last_done]
        if e.kind == "STATE_SET" and "(battery_level)" in e.subject
    ]  # fmt: skip
    assert readings, "the battery did not change between the two deliveries"
    # the plan for both goals ran to its end: nothing planned after the first delivery
    rounds = {"PLANNING", "PLAN_START", "REPLAN"}
    assert [(e.kind, e.data) for e in events[first_done:] if e.kind in rounds] == []
    last = [e for e in events if e.kind == "PLAN_START"][-1]
    assert sorted(last.data["goals"]) == sorted((lab, office))
    # each round names what asked for it: the goals added, not a reading
    allowed = {"the executive started", f"goal {lab} added", f"goal {office} added"}
    for planning in (e for e in events if e.kind == "PLANNING"):
        assert set(planning.data["reason"].split("; ")) <= allowed, planning.data
