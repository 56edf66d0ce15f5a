"""Plans as partial orders: precedences from UP's STN, ground conditions and effects."""

from __future__ import annotations

import itertools

from executive.planning.expression import Atom, WorldState
from executive.planning.goals import GoalSpec
from executive.planning.partial_order import Precedence, Timepoint, apply
from executive.planning.planner import Planner, PlanningTask
from knowledge.records import Fact
from tests.executive.planning.planning_cases import (
    TRANSPORT_DOMAIN,
    TRANSPORT_PROBLEM,
    expr,
    kairos_fixture,  # noqa: F401 (a fixture)
    usecase_task,
    world,
)


def test_each_step_of_a_sequential_use_case_plan_waits_for_the_end_of_the_one_before(
    kairos: Planner,
) -> None:
    result = kairos.solve(usecase_task("(picture_taken lab)", "(robot_at office)"))
    assert result.plan is not None
    steps = result.plan.steps
    assert "take_picture(lab)" in [s.label for s in steps]
    assert steps[0].after == ()
    for before, step in itertools.pairwise(steps):
        assert Precedence(before.index, Timepoint.END) in step.after
        assert step.start >= before.start + (before.duration or 0) - 1e-6


def test_steps_carry_their_ground_conditions_and_effects(kairos: Planner) -> None:
    result = kairos.solve(usecase_task("(robot_at lab)"))
    assert result.plan is not None
    (move,) = result.plan.steps
    assert move.bindings == {"from": "dock", "to": "lab"}
    assert move.at_start == Atom("robot_at", ("dock",))
    assert move.over_all == Atom("connected", ("dock", "lab"))
    assert move.duration == 4.0
    state = WorldState([Fact("robot_at", ("dock",))])
    add, remove = apply(move.start_effects, state)
    assert (add, remove) == ([], [Fact("robot_at", ("dock",), False)])
    assert apply(move.end_effects, state) == ([Fact("robot_at", ("lab",))], [])


def test_the_lift_is_called_while_the_robot_drives_and_the_ride_waits_for_both(
    kairos: Planner,
) -> None:
    goal = GoalSpec(1, expr("(robot_at lab)", TRANSPORT_DOMAIN, TRANSPORT_PROBLEM))
    task = PlanningTask(TRANSPORT_DOMAIN, world(TRANSPORT_DOMAIN, TRANSPORT_PROBLEM), (goal,))
    result = kairos.solve(task)
    assert result.ok and result.plan is not None
    by_label = {s.label: s for s in result.plan.steps}
    assert {s.label for s in result.plan.roots()} == {
        "call_lift(hall1, hall0)",
        "drive(dock, hall0)",
    }
    ride = by_label["ride_lift(hall0, hall1)"]
    waits = {(result.plan.steps[p.step].label, p.at) for p in ride.after}
    assert waits == {
        ("call_lift(hall1, hall0)", Timepoint.END),
        ("drive(dock, hall0)", Timepoint.END),
    }


def test_deadline_bookkeeping_is_not_a_step(kairos: Planner) -> None:
    result = kairos.solve(usecase_task(("(picture_taken lab)", {"deadline": 30.0})))
    assert result.plan is not None
    assert [s.action for s in result.plan.steps] == ["move_to", "take_picture"]
    assert [r.action for r in result.plan.records()] == ["move_to", "take_picture"]
