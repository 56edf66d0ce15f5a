"""The engine chosen by what the problem needs (``auto``), a portfolio of real engines,
and the one-line refusal when no installed engine supports a problem (issue 28)."""

from __future__ import annotations

from fractions import Fraction
from pathlib import Path
from typing import Any

import pytest

from executive import fast_start
from executive.planning.goals import GoalSpec
from executive.planning.metric import Metric, read_metric
from executive.planning.planner import Planner, PlanningTask, PlanStatus
from executive.planning.portfolio import Portfolio, planner_for
from executive.planning.problem import read_problem
from knowledge.description import PlannerSpec
from knowledge.errors import DomainError, PlanningError
from knowledge.robot import read_robot
from tests.executive.planning.planning_cases import TRANSPORT_DOMAIN, TRANSPORT_PROBLEM, world

FEATURES = Path(__file__).parent / "features"


def feature_task(feature: str) -> PlanningTask:
    domain = FEATURES / f"{feature}.domain.pddl"
    found, goal, metric = read_problem(domain, FEATURES / f"{feature}.problem.pddl")
    return PlanningTask(domain, found, (GoalSpec(1, goal),), metric=metric)


def transport_task(goal: str, metric: Metric | None = None) -> PlanningTask:
    from tests.executive.planning.planning_cases import expr

    target = expr(goal, TRANSPORT_DOMAIN, TRANSPORT_PROBLEM)
    own = world(TRANSPORT_DOMAIN, TRANSPORT_PROBLEM)
    return PlanningTask(TRANSPORT_DOMAIN, own, (GoalSpec(1, target),), metric=metric)


@pytest.fixture(scope="module")
def installed() -> dict[str, Any]:
    """The engines installed here, by name → their unified-planning class, as the
    planner's worker sees them."""
    fast_start.import_unified_planning()
    from executive.planning.planner_jobs import PlannerJobs

    return PlannerJobs(Path("/dev/null")).available()


def durative_problem(timed_goal: bool, conditional: bool) -> Any:
    """A real unified-planning problem with a timed goal and/or a conditional effect."""
    from unified_planning.shortcuts import (
        BoolType,
        DurativeAction,
        EndTiming,
        Fluent,
        GlobalStartTiming,
        Problem,
        StartTiming,
    )

    ready, done, loud = (Fluent(n, BoolType()) for n in ("ready", "done", "loud"))
    act = DurativeAction("act")
    act.set_fixed_duration(2)
    act.add_condition(StartTiming(), ready)
    act.add_effect(EndTiming(), done, True)
    if conditional:
        act.add_effect(EndTiming(), loud, True, condition=ready)
    problem = Problem("p")
    for f in (ready, done, loud):
        problem.add_fluent(f, default_initial_value=False)
    problem.set_initial_value(ready, True)
    problem.add_action(act)
    if timed_goal:
        problem.add_timed_goal(GlobalStartTiming(Fraction(5)), done)
    else:
        problem.add_goal(done)
    return problem


def test_auto_takes_the_first_installed_engine_that_supports_the_problem(
    installed: dict[str, Any],
) -> None:
    from executive.planning.engine_choice import choose

    plain = durative_problem(timed_goal=False, conditional=True)
    assert choose(list(installed), installed, plain.kind.features).engine == "kairos"
    timed = durative_problem(timed_goal=True, conditional=False)  # kairos has no timed goals
    assert choose(list(installed), installed, timed.kind.features).engine == "aries"


def test_a_problem_no_installed_engine_supports_gets_a_one_line_refusal(
    installed: dict[str, Any],
) -> None:
    from executive.planning.engine_choice import choose

    both = durative_problem(timed_goal=True, conditional=True)
    choice = choose(list(installed), installed, both.kind.features)
    assert choice.engine == ""
    assert "\n" not in choice.refusal
    assert "kairos does not support timed goals (TIMED_GOALS)" in choice.refusal
    assert "aries does not support conditional effects (CONDITIONAL_EFFECTS)" in choice.refusal
    assert choice.refusal.endswith("(no installed engine supports all of this problem)")


def test_auto_plans_with_the_engine_it_chose_and_says_which() -> None:
    with Planner("auto", timeout=20) as planner:
        result = planner.solve(feature_task("conditional"))
    assert result.ok, result.log
    assert result.engine == "kairos"


def test_a_chosen_engine_that_lacks_a_feature_is_a_refusal_not_a_search() -> None:
    with Planner("aries", timeout=20) as planner:
        result = planner.solve(feature_task("conditional"))
    assert result.status is PlanStatus.UNSUPPORTED
    assert result.reason == (
        "aries does not support conditional effects (CONDITIONAL_EFFECTS) "
        "(installed engines that do: kairos)"
    )


def test_a_portfolio_takes_the_plan_of_the_engine_that_can_when_another_refuses() -> None:
    with Portfolio(["aries", "kairos"], timeout=20) as portfolio:
        portfolio.start(FEATURES / "conditional.domain.pddl")
        result = portfolio.solve(feature_task("conditional"))
    assert result.ok, result.log
    assert result.engine == "kairos"
    assert result.plan is not None and [s.label for s in result.plan.steps] == ["load(big)"]


def test_a_portfolio_minimising_the_makespan_takes_the_shortest_plan_of_its_engines() -> None:
    task = transport_task("(crate_at parcel lab)", read_metric("minimize makespan"))
    spans = {}
    for engine in ("kairos", "aries"):
        with Planner(engine, timeout=6) as alone:
            result = alone.solve(task)
        assert result.ok and result.plan is not None, result.log
        spans[engine] = result.plan.makespan
    with Portfolio(["kairos", "aries"], timeout=6) as portfolio:
        result = portfolio.solve(task)
    assert result.ok and result.plan is not None, result.log
    assert result.plan.makespan == min(spans.values())
    assert result.engine in {e for e, span in spans.items() if span == result.plan.makespan}


def test_a_portfolio_without_a_plan_gives_every_engines_reason_on_one_line() -> None:
    with Portfolio(["aries", "fast-downward"], timeout=20) as portfolio:
        result = portfolio.solve(feature_task("conditional"))
    assert result.status is PlanStatus.UNSUPPORTED
    assert result.engine == "portfolio"
    assert "\n" not in result.reason
    assert "aries does not support conditional effects" in result.reason
    assert "fast-downward does not support durative actions" in result.reason


def test_a_portfolio_of_unknown_engines_is_refused() -> None:
    with pytest.raises(PlanningError, match="a portfolio runs engines, not 'auto'"):
        Portfolio(["kairos", "auto"])


def test_the_robot_description_chooses_a_portfolio_and_a_metric(tmp_path: Path) -> None:
    (tmp_path / "robot.yaml").write_text(
        f"robot: r\ndomain: {TRANSPORT_DOMAIN}\n"
        "planner:\n  portfolio: [kairos, aries]\n  metric: minimize makespan\n  timeout: 5\n"
    )
    robot, findings = read_robot(tmp_path / "robot.yaml")
    assert robot is not None and not [f for f in findings if f.is_error], findings
    assert robot.planner.portfolio == ("kairos", "aries")
    planner = planner_for(robot.planner)
    assert isinstance(planner, Portfolio)
    assert planner.metric == Metric() and planner.timeout == 5
    assert planner.engines == ["kairos", "aries"]


@pytest.mark.parametrize(
    ("planner", "error"),
    [
        ("{metric: fastest}", "metric 'fastest' must be 'minimize makespan'"),
        ("{portfolio: [kairos, kiros]}", "unknown planner engine 'kiros'"),
        ("{portfolio: [portfolio]}", "a portfolio runs engines, not 'portfolio'"),
    ],
)
def test_a_wrong_planner_entry_is_one_line_with_its_line(
    tmp_path: Path, planner: str, error: str
) -> None:
    (tmp_path / "robot.yaml").write_text(
        f"robot: r\ndomain: {TRANSPORT_DOMAIN}\nplanner: {planner}\n"
    )
    _, findings = read_robot(tmp_path / "robot.yaml")
    (found,) = [f for f in findings if f.is_error]
    assert error in str(found)
    assert ":3:" in str(found)


def test_a_metric_is_read_as_a_robot_description_writes_it() -> None:
    assert read_metric("minimize makespan") == Metric()
    assert read_metric("minimize (total-time)") == Metric()
    assert str(read_metric("maximize (+ (fuel r1) 2)")) == "maximize (+ (fuel r1) 2)"
    with pytest.raises(DomainError, match="metric 'smallest x'"):
        read_metric("smallest x")


def test_the_default_planner_is_auto() -> None:
    spec = PlannerSpec()
    assert spec.engine == "auto"
    planner = planner_for(spec)
    assert type(planner) is Planner and planner.engine == "auto" and planner.metric is None


def test_the_docs_say_which_pddl_features_each_installed_engine_supports(
    installed: dict[str, Any],
) -> None:
    from tests.engine_features import FEATURES, documented_table, rows

    names, cells = documented_table()
    assert list(cells) == list(FEATURES)
    assert set(installed) <= set(names)
    for feature, *computed in rows(installed):
        for engine, value in zip(installed, computed, strict=True):
            assert cells[feature][names.index(engine)] == value, (feature, engine)


def test_an_anytime_engine_gives_its_best_plan_at_the_timeout() -> None:
    first_found = transport_task("(and (crate_at parcel lab) (robot_at dock))")
    best = transport_task(
        "(and (crate_at parcel lab) (robot_at dock))", read_metric("minimize makespan")
    )
    with Planner("aries", timeout=15) as aries:
        first = aries.solve(first_found)
        result = aries.solve(best)
    assert first.ok and first.plan is not None, first.log
    assert result.ok and result.plan is not None, result.log
    assert result.plan.makespan <= first.plan.makespan
