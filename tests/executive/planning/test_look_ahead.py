"""Watching the plan ahead: a change that blocks a step still to come is found at once;
one that breaks nothing is not."""

from __future__ import annotations

import pytest

from executive.planning.goals import GoalSpec
from executive.planning.look_ahead import Ahead, look_ahead
from executive.planning.partial_order import PartialOrderPlan
from executive.planning.planner import Planner, PlanningTask
from knowledge.records import Fact
from tests.executive.planning.planning_cases import (
    TRANSPORT_DOMAIN,
    TRANSPORT_PROBLEM,
    expr,
    kairos_fixture,  # noqa: F401 (a fixture)
    world,
)

DELIVERY = "(crate_at parcel lab)"


@pytest.fixture(scope="module", name="delivery")
def delivery_fixture(kairos: Planner) -> PartialOrderPlan:
    goal = GoalSpec(1, expr(DELIVERY, TRANSPORT_DOMAIN, TRANSPORT_PROBLEM))
    task = PlanningTask(TRANSPORT_DOMAIN, world(TRANSPORT_DOMAIN, TRANSPORT_PROBLEM), (goal,))
    result = kairos.solve(task)
    assert result.plan is not None, result.reason
    return result.plan


def facts_without(*gone: Fact) -> list[Fact]:
    return [f for f in world(TRANSPORT_DOMAIN, TRANSPORT_PROBLEM).facts if f not in gone]


def ahead(plan: PartialOrderPlan) -> list[Ahead]:
    return [Ahead(s, started=False) for s in plan.steps]


def goal() -> list[object]:
    return [expr(DELIVERY, TRANSPORT_DOMAIN, TRANSPORT_PROBLEM)]


def test_the_plan_works_in_the_world_it_was_made_for(delivery: PartialOrderPlan) -> None:
    facts = facts_without()
    changed = {(f.name, f.args) for f in facts}
    assert look_ahead(ahead(delivery), facts, changed, goal()) is None  # type: ignore[arg-type]


def test_a_road_blocked_ahead_is_found_at_the_step_that_needs_it(
    delivery: PartialOrderPlan,
) -> None:
    road = Fact("road", ("store", "hall0"))
    blocked = look_ahead(ahead(delivery), facts_without(road), {("road", road.args)})
    assert blocked is not None
    assert blocked.step is not None and blocked.step.label == "drive(store, hall0)"
    assert str(blocked) == (
        "step drive(store, hall0) ahead: over-all condition (road store hall0) will not "
        "hold ((road store hall0) changed)"
    )


def test_a_change_that_breaks_nothing_ahead_is_no_reason_to_replan(
    delivery: PartialOrderPlan,
) -> None:
    road = Fact("road", ("lab", "hall1"))  # the way back, which the plan does not take
    assert look_ahead(ahead(delivery), facts_without(road), {("road", road.args)}) is None


def test_a_condition_a_step_before_it_makes_true_is_not_blocked(
    delivery: PartialOrderPlan,
) -> None:
    # the robot is already at the store: drive(dock, store) cannot start, but its own
    # failure names (robot_at dock), which did not change; what the plan needs later
    # (robot_at store) is given by that drive in the simulation
    moved = [*facts_without(Fact("robot_at", ("dock",))), Fact("robot_at", ("store",))]
    assert look_ahead(ahead(delivery), moved, {("robot_at", ("store",))}) is None


def test_a_broken_goal_is_found_after_the_last_step(delivery: PartialOrderPlan) -> None:
    steps = [a for a in ahead(delivery) if a.step.action != "drop"]
    blocked = look_ahead(steps, facts_without(), {("crate_at", ("parcel", "lab"))}, goal())  # type: ignore[arg-type]
    assert blocked is not None and blocked.step is None
    assert str(blocked).startswith("the plan's goal: goal condition (crate_at parcel lab)")
