"""When unreachable goals are looked at again, and which maintenance goals broke."""

from __future__ import annotations

from executive.planning.expression import WorldState
from executive.planning.goal_watch import GoalWatch
from knowledge.records import Fact, Goal, GoalState
from tests.executive.planning.planning_cases import expr


def test_an_unreachable_goal_is_looked_at_only_after_the_world_changed() -> None:
    watch = GoalWatch()
    assert watch.due([3], now=0.0) == ([], None)
    watch.world_changed([3])
    assert watch.due([3], now=0.0) == ([3], None)


def test_a_flapping_fact_costs_one_look_per_doubling_interval() -> None:
    watch = GoalWatch(first=1.0, longest=8.0)
    looks = []
    for tick in range(400):  # a fact that flaps ten times a second for 40 seconds
        now = tick / 10
        watch.world_changed([3])
        due, _ = watch.due([3], now)
        if due:
            looks.append(now)
            watch.looked(3, now)
    assert looks == [0.0, 1.0, 3.0, 7.0, 15.0, 23.0, 31.0, 39.0]


def test_the_next_look_is_due_when_its_interval_ends() -> None:
    watch = GoalWatch(first=2.0)
    watch.world_changed([1, 2])
    watch.looked(1, now=10.0)
    watch.world_changed([1, 2])
    assert watch.due([1, 2], now=10.5) == ([2], 12.0)


def kept(goal_id: int, text: str, state: GoalState = GoalState.ACHIEVED) -> Goal:
    return Goal(goal_id, text, state, keep=True)


def test_an_achieved_maintenance_goal_that_no_longer_holds_is_broken() -> None:
    home, lab = kept(1, "(robot_at dock)"), kept(2, "(robot_at lab)", GoalState.PENDING)
    once = Goal(3, "(robot_at dock)", GoalState.ACHIEVED)
    expressions = {g.id: expr(g.expression) for g in (home, lab, once)}
    state = WorldState([Fact("robot_at", ("lab",))])
    assert GoalWatch().broken([home, lab, once], expressions, state) == [home]


def test_a_maintenance_goal_is_not_reposted_twice_within_its_interval() -> None:
    watch = GoalWatch(repost_interval=2.0)
    assert watch.may_repost(1, now=5.0) is None
    watch.reposted(1, now=5.0)
    assert watch.may_repost(1, now=6.0) == 7.0
    assert watch.may_repost(1, now=7.0) is None
