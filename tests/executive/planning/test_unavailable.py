"""Objects that cannot act now (a fleet's lost robots) are left out of every step, with
a real planner; the plan's steps do not carry the planner's own condition."""

from __future__ import annotations

import dataclasses

from executive.planning.goals import GoalSpec
from executive.planning.planner import Planner, PlanningTask
from executive.planning.problem import build, read_world
from executive.planning.unavailable import restrict
from knowledge.domain import parse
from tests.conftest import ROOT
from tests.executive.planning.planning_cases import expr

DEPOT = ROOT / "examples" / "fleet" / "depot.pddl"
FLOOR = ROOT / "examples" / "fleet" / "problem.pddl"


def task(goal: str, unavailable: frozenset[str] = frozenset()) -> PlanningTask:
    world = dataclasses.replace(read_world(DEPOT, FLOOR)[0], unavailable=unavailable)
    return PlanningTask(DEPOT, world, (GoalSpec(1, expr(goal, DEPOT, FLOOR)),))


def actors(result_steps: tuple[object, ...]) -> set[str]:
    return {step.args[0] for step in result_steps}  # type: ignore[attr-defined]


def test_a_plan_gives_no_step_to_an_unavailable_robot() -> None:
    goal = "(and (crate_at parcel1 lab) (crate_at parcel2 office))"
    with Planner("kairos", timeout=20.0) as kairos:
        kairos.start(DEPOT)
        without = kairos.solve(task(goal, frozenset({"r1", "r3"})))
        assert without.plan is not None, without.reason
        assert actors(without.plan.steps) == {"r2"}
        # nothing of the planner's condition reaches the steps the executor checks
        assert all("dura_" not in str(s.at_start) for s in without.plan.steps)
        none = kairos.solve(task(goal, frozenset({"r1", "r2", "r3"})))
        assert none.plan is None


def test_only_the_parameters_that_may_hold_an_unavailable_object_are_guarded() -> None:
    world = dataclasses.replace(read_world(DEPOT, FLOOR)[0], unavailable=frozenset({"r1"}))
    problem = build(parse(DEPOT), world, ())
    drive = problem.action("drive")
    guarded = [str(c) for cs in drive.conditions.values() for c in cs if "dura_" in str(c)]
    assert guarded == ["dura_available_robot(r)"]
    fluent = problem.fluent("dura_available_robot")
    values = {str(k): v.bool_constant_value() for k, v in problem.initial_values.items()
              if k.fluent() == fluent}  # fmt: skip
    assert values == {
        "dura_available_robot(r1)": False,
        "dura_available_robot(r2)": True,
        "dura_available_robot(r3)": True,
    }
    unchanged = build(parse(DEPOT), read_world(DEPOT, FLOOR)[0], ())
    restrict(unchanged, ["nobody"])  # an object the problem lacks changes nothing
    assert not unchanged.has_fluent("dura_available_robot")
