"""A fleet's only robot lost mid-step: its goal is unreachable while no robot can act,
and reached once the robot is back (real executive, components and planner)."""

from __future__ import annotations

from pathlib import Path

import pytest

from knowledge.records import GoalState
from tests.conftest import wait_for
from tests.e2e.test_fleet import depot

pytestmark = pytest.mark.slow


def test_a_goal_unreachable_while_the_only_robot_is_lost_is_reached_when_it_is_back(
    tmp_path: Path,
) -> None:
    with depot(tmp_path, ["r1"]) as (fleet, (r1,)):
        goal = fleet.submit_goal("(crate_at parcel1 lab)")
        fleet.wait_for_event("START", "drive(r1,", timeout=60)
        r1.kill()
        assert wait_for(lambda: fleet.goal(goal).state is GoalState.UNREACHABLE, 30)
        r1.start()
        fleet.wait_for(goal, "achieved", timeout=120)
        assert [e.subject for e in fleet.events("ROBOT_LOST")] == ["r1"]
        assert "(crate_at parcel1 lab)" in fleet.facts("crate_at")
