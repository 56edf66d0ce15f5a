"""When no plan reaches every goal: the best goals by priority, a reason for the rest."""

from __future__ import annotations

from executive.planning.oversubscription import plan_goals
from executive.planning.planner import Planner
from tests.executive.planning.planning_cases import kairos_fixture, usecase_task  # noqa: F401


def test_all_reachable_goals_cost_one_planner_call(kairos: Planner) -> None:
    outcome = plan_goals(kairos, usecase_task("(picture_taken lab)", "(robot_at office)"))
    assert outcome.ok
    assert outcome.planned == (1, 2)
    assert outcome.unreachable == {}
    assert outcome.calls == 1


def test_an_unreachable_goal_is_given_up_with_what_it_misses_and_the_others_are_planned(
    kairos: Planner,
) -> None:
    outcome = plan_goals(
        kairos, usecase_task("(picture_taken lab)", "(picture_taken dock)", "(robot_at office)")
    )
    assert outcome.ok
    assert sorted(outcome.planned) == [1, 3]
    assert list(outcome.unreachable) == [2]
    assert outcome.unreachable[2].startswith(
        "no plan reaches it from the current state: (picture_taken dock) cannot become true: "
        "take_picture(dock) needs (photographable dock) (kairos "
    ), outcome.unreachable[2]


def test_of_two_goals_that_exclude_each_other_the_higher_priority_one_is_kept(
    kairos: Planner,
) -> None:
    outcome = plan_goals(
        kairos,
        usecase_task(
            ("(robot_at lab)", {"priority": 1}),
            ("(robot_at office)", {"priority": 5}),
            ("(picture_taken lab)", {"priority": 1}),
        ),
    )
    assert outcome.ok
    assert outcome.planned == (2, 3)
    assert outcome.unreachable == {
        1: "no plan reaches it together with goal 2 (kept first by priority)"
    }


def test_a_search_that_runs_out_of_time_gives_the_goals_left_that_reason(
    kairos: Planner,
) -> None:
    # both pictures by 7 s cannot be, and Kairos cannot prove it quickly
    outcome = plan_goals(
        kairos,
        usecase_task(
            ("(picture_taken lab)", {"deadline": 7.0, "priority": 1}),
            ("(picture_taken office)", {"deadline": 7.5, "priority": 5}),
        ),
        budget=2.0,
    )
    assert outcome.ok
    assert outcome.planned == (2,)
    assert (
        "no plan in time" in outcome.unreachable[1] or "ran out of time" in outcome.unreachable[1]
    )


def test_a_goal_no_plan_reaches_even_alone_says_so(kairos: Planner) -> None:
    outcome = plan_goals(kairos, usecase_task("(picture_taken dock)"))
    assert not outcome.ok
    assert outcome.planned == ()
    assert outcome.unreachable[1].startswith("no plan reaches it from the current state")
