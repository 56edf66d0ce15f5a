from __future__ import annotations

import dataclasses
import itertools
from collections.abc import Collection, Sequence
from typing import Any

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from executive.tasks.schedule import Request, ScheduleResult, ScheduleStatus
from executive.tasks.scheduler import Scheduler
from knowledge.asp import Asp
from knowledge.availability import Availability
from knowledge.description import FunctionalitySpec
from tests.executive.tasks.scheduling_cases import functionality, generate, request, usecase

LIDAR = {"obstacle_scan": "lidar_filter", "laser_scan": "lidar", "base": "robot_base"}
CAM = {"obstacle_scan": "cam_to_lidar", "camera": "cam", "base": "robot_base"}


def scheduler(*without: str, **changes: object) -> Scheduler:
    """The use-case robot without some functionalities, with changed fields of others."""
    functionalities, _ = usecase()
    return Scheduler(
        dataclasses.replace(f, **changes.get(f.name, {}))  # type: ignore[arg-type]
        for f in functionalities.values()
        if f.name not in without
    )


def move_to(request_id: str, **constraints: Any) -> Request:
    return request(usecase()[1]["move_to"], request_id, **constraints)


def take_picture(request_id: str, **constraints: Any) -> Request:
    constraints.setdefault("duration", 2.0)
    return request(usecase()[1]["take_picture"], request_id, **constraints)


def assert_valid(
    functionalities: Collection[FunctionalitySpec],
    requests: Sequence[Request],
    faulty: Collection[str],
    result: ScheduleResult,
) -> None:
    """Every constraint of a schedule holds, and every request is answered."""
    by_name = {f.name: f for f in functionalities}
    usable = Availability.of(functionalities, faulty).usable
    by_id = {r.id: r for r in requests}
    assert set(result.assignments).isdisjoint(result.cancelled)
    assert set(result.assignments) | set(result.cancelled) == set(by_id)
    for a in result.assignments.values():
        r = by_id[a.request]
        assert set(r.needs) <= set(a.providers)
        for capability, name in a.providers.items():
            assert name in usable
            assert capability in by_name[name].provides
            assert set(by_name[name].requires) <= set(a.providers)
        assert a.start >= r.earliest - 1e-9
        assert a.end == pytest.approx(a.start + r.duration)
        if r.running:
            assert a.start == 0
        if r.deadline is not None:
            assert a.end <= r.deadline + 1e-9
        for partner in r.together:
            assert result.assignments[partner].start == a.start
        # as early as its order allows: at its release, or when a predecessor (of its
        # start-together group) ends
        group = [a, *(result.assignments[p] for p in r.together)]
        bounds = [by_id[g.request].earliest for g in group]
        bounds += [result.assignments[p].end for g in group for p in g.after]
        assert a.start == pytest.approx(max(bounds), abs=0.1)
    for a, b in itertools.combinations(result.assignments.values(), 2):
        held_a = {by_id[a.request].behavior} | {
            f for f in a.functionalities if not by_name[f].shareable
        }
        held_b = {by_id[b.request].behavior} | {
            f for f in b.functionalities if not by_name[f].shareable
        }
        if held_a & held_b:
            assert a.end <= b.start + 1e-9 or b.end <= a.start + 1e-9, (a, b)


# --- the thesis scenarios (chapter 7), scheduling side ---------------------------------


def test_scenario_1_move_to_runs_on_lidar_and_lidar_filter() -> None:
    result = scheduler("cam", "cam_to_lidar").schedule([move_to("1")])
    assert result.status is ScheduleStatus.OPTIMAL
    assert result.assignments["1"].providers == LIDAR
    assert result.assignments["1"].start == 0


def test_scenario_1_without_an_alternative_to_a_faulty_lidar_the_request_is_cancelled() -> None:
    running = move_to("1", running=True, configuration=LIDAR)
    result = scheduler("cam", "cam_to_lidar").schedule([running], faulty={"lidar"})
    assert result.assignments == {}
    assert result.cancelled == {
        "1": "no provider for capability 'obstacle_scan': "
        "lidar_filter requires 'laser_scan' (lidar is permanently faulty)"
    }


def test_scenario_2_the_higher_rated_lidar_is_chosen_while_it_works() -> None:
    result = scheduler().schedule([move_to("1")])
    assert result.assignments["1"].providers == LIDAR


def test_scenario_2_a_permanently_faulty_lidar_switches_move_to_to_cam_to_lidar() -> None:
    running = move_to("1", running=True, configuration=LIDAR)
    result = scheduler().schedule([running], faulty={"lidar"})
    assert result.status is ScheduleStatus.OPTIMAL
    assert result.assignments["1"].providers == CAM
    assert result.assignments["1"].start == 0
    assert result.cost["changes"] == 4  # lidar_filter, lidar out; cam_to_lidar, cam in


def test_scenario_3_two_move_to_run_one_after_the_other_on_the_same_lidar() -> None:
    result = scheduler().schedule([move_to("1", duration=30.0), move_to("2", duration=20.0)])
    first, second = result.assignments["1"], result.assignments["2"]
    assert first.providers == second.providers == LIDAR
    assert (first.start, first.end) == (0, 30)
    assert (second.start, second.end) == (30, 50)
    assert second.after == {"1"}
    assert list(result.assignments) == ["1", "2"]


def test_scenario_3_the_non_shareable_robot_base_serialises_behaviors_that_need_it() -> None:
    functionalities, behaviors = usecase()
    dock = dataclasses.replace(behaviors["take_picture"], name="dock", requires=("base",))
    requests = [move_to("1"), request(dock, "2")]
    serial = Scheduler(functionalities.values()).schedule(requests)
    assert serial.assignments["2"].start == serial.assignments["1"].end
    shared_base = scheduler(robot_base={"shareable": True}).schedule(requests)
    assert shared_base.assignments["2"].start == shared_base.assignments["1"].start == 0


def test_scenario_4_move_to_on_cam_to_lidar_shares_cam_with_take_picture() -> None:
    requests = [move_to("1", running=True, configuration=LIDAR), take_picture("2")]
    before = scheduler().schedule(requests)
    assert before.assignments["1"].providers == LIDAR
    assert before.assignments["2"].providers == {"camera": "cam"}
    assert before.assignments["2"].start == 0
    after = scheduler().schedule(requests, faulty={"lidar"})
    assert after.assignments["1"].providers == CAM
    assert after.assignments["2"].providers == {"camera": "cam"}
    assert after.assignments["2"].start == 0  # side by side: cam is shareable


def test_scenario_4_repeated_take_picture_requests_wait_for_each_other_not_for_move_to() -> None:
    requests = [
        move_to("1", running=True, configuration=CAM),
        take_picture("2", running=True, configuration={"camera": "cam"}),
        take_picture("3"),
    ]
    result = scheduler().schedule(requests, faulty={"lidar"})
    assert result.assignments["1"].providers == CAM
    assert result.assignments["3"].start == result.assignments["2"].end
    assert result.assignments["3"].after == {"2"}


# --- constraints -------------------------------------------------------------------------


def test_a_request_starts_no_earlier_than_its_earliest_start() -> None:
    result = scheduler().schedule([move_to("1", earliest=12.5)])
    assert result.assignments["1"].start == 12.5


def test_durations_between_ticks_round_up_so_that_tasks_never_overlap() -> None:
    result = scheduler().schedule([move_to("1", duration=2.55), move_to("2", duration=1.0)])
    assert result.assignments["1"].end == 2.55
    assert result.assignments["2"].start == 2.6


def test_a_deadline_its_own_duration_cannot_meet_cancels_the_request() -> None:
    result = scheduler().schedule([move_to("1", earliest=5.0, deadline=12.0)])
    assert result.cancelled == {
        "1": "deadline 12 s cannot be met: earliest start 5 s + expected duration 10 s"
    }


def test_a_deadline_a_running_task_makes_unreachable_cancels_the_request_and_names_it() -> None:
    requests = [move_to("1", running=True, configuration=LIDAR), move_to("2", deadline=15.0)]
    result = scheduler().schedule(requests)
    assert set(result.assignments) == {"1"}
    assert result.cancelled == {
        "2": "cannot end by its deadline 15 s: '1' (running) holds move_to, robot_base from 0 to 10 s"
    }


def test_a_deadline_reorders_requests_that_came_later() -> None:
    result = scheduler().schedule([move_to("1"), move_to("2", deadline=10.0)])
    assert result.complete
    assert result.assignments["2"].start == 0
    assert result.assignments["1"].start == 10
    assert result.cost["out_of_order"] == 1


def test_of_two_requests_that_only_fit_one_at_a_time_before_their_deadlines_one_is_cancelled() -> (
    None
):
    result = scheduler().schedule([move_to("1", deadline=15.0), move_to("2", deadline=15.0)])
    assert len(result.assignments) == 1
    ((dropped, reason),) = result.cancelled.items()
    kept = next(iter(result.assignments))
    assert reason == (
        f"cannot end by its deadline 15 s: '{kept}' holds move_to, robot_base from 0 to 10 s"
    )
    assert dropped != kept


def test_a_cancellation_names_every_request_in_the_way_up_to_four() -> None:
    requests = [move_to(f"m{i}", deadline=40.0) for i in range(7)]
    result = scheduler().schedule(requests)
    assert list(result.assignments) == ["m0", "m1", "m2", "m3"]
    assert result.cancelled["m4"] == (
        "cannot end by its deadline 40 s: '"
        "m0' holds move_to, robot_base from 0 to 10 s; 'm1' holds move_to, robot_base from 10 to"
        " 20 s; 'm2' holds move_to, robot_base from 20 to 30 s; 'm3' holds move_to, robot_base"
        " from 30 to 40 s"
    )


def test_a_cancellation_names_only_what_stands_in_the_way_within_the_deadline() -> None:
    requests = [
        move_to("1", running=True, configuration=LIDAR, duration=30.0),
        take_picture("2"),
        take_picture("3", deadline=1.5),  # shorter than its duration: never
        move_to("4", deadline=20.0),
    ]
    result = scheduler().schedule(requests)
    assert result.cancelled == {
        "3": "deadline 1.5 s cannot be met: earliest start 0 s + expected duration 2 s",
        "4": "cannot end by its deadline 20 s: '1' (running) holds move_to, robot_base"
        " from 0 to 30 s",
    }


def test_requests_that_start_together_start_at_the_same_time() -> None:
    requests = [move_to("1", together=("2",)), take_picture("2", earliest=5.0, together=("1",))]
    result = scheduler().schedule(requests)
    assert result.assignments["1"].start == result.assignments["2"].start == 5


def test_a_start_together_partner_that_cannot_run_takes_its_partner_with_it() -> None:
    requests = [move_to("1", together=("2",)), take_picture("2", together=("1",))]
    result = scheduler().schedule(requests, faulty={"cam"})
    assert result.cancelled == {
        "1": "must start together with '2', which cannot be scheduled: "
        "no provider for capability 'camera': cam is permanently faulty",
        "2": "no provider for capability 'camera': cam is permanently faulty",
    }


def test_a_start_together_partner_that_misses_its_deadline_takes_its_partner_with_it() -> None:
    requests = [
        take_picture("0", running=True, configuration={"camera": "cam"}, duration=30.0),
        move_to("1", together=("2",)),
        take_picture("2", together=("1",), deadline=10.0),
    ]
    result = scheduler().schedule(requests)
    blocked = "cannot end by its deadline 10 s: '0' (running) holds take_picture from 0 to 30 s"
    assert result.cancelled == {
        "1": f"must start together with '2', which cannot be scheduled: {blocked}",
        "2": blocked,
    }


def test_requests_that_must_start_together_but_share_robot_base_are_cancelled() -> None:
    requests = [move_to("1", together=("2",)), move_to("2", together=("1",))]
    result = scheduler().schedule(requests)
    assert result.assignments == {}
    assert result.cancelled == {
        "1": "cannot start at the same time as '2': "
        "both need move_to, robot_base, which serve one task at a time",
        "2": "cannot start at the same time as '1': "
        "both need move_to, robot_base, which serve one task at a time",
    }


def test_an_unknown_start_together_partner_cancels_the_request() -> None:
    result = scheduler().schedule([move_to("1", together=("9",))])
    assert result.cancelled == {"1": "must start together with unknown request '9'"}


def test_a_permanently_faulty_behavior_cancels_its_requests() -> None:
    result = scheduler().schedule([move_to("1"), take_picture("2")], faulty={"move_to"})
    assert result.cancelled == {"1": "behavior move_to is permanently faulty"}
    assert set(result.assignments) == {"2"}


def test_running_tasks_that_can_no_longer_both_run_lose_one_of_them() -> None:
    # two behaviors share the only remaining provider of obstacle_scan, made exclusive
    _, behaviors = usecase()
    avoid = dataclasses.replace(
        behaviors["take_picture"], name="avoid", requires=("obstacle_scan",)
    )
    sched = scheduler(cam_to_lidar={"shareable": False})
    requests = [
        move_to("1", running=True, configuration=LIDAR),
        request(
            avoid,
            "2",
            running=True,
            configuration={"obstacle_scan": "lidar_filter", "laser_scan": "lidar"},
        ),
    ]
    result = sched.schedule(requests, faulty={"lidar"})
    assert len(result.assignments) == 1
    ((dropped, reason),) = result.cancelled.items()
    kept = "2" if dropped == "1" else "1"
    assert reason == f"cannot keep running: '{kept}' (running) holds cam_to_lidar from 0 to 10 s"
    assert result.cost["running_cancelled"] == 1


# --- preferences -------------------------------------------------------------------------


def test_a_running_configuration_stays_even_when_a_better_one_becomes_available() -> None:
    # move_to fell back to cam_to_lidar; lidar is repaired, move_to keeps its configuration
    result = scheduler().schedule([move_to("1", running=True, configuration=CAM), move_to("2")])
    assert result.assignments["1"].providers == CAM
    assert result.assignments["2"].providers == LIDAR
    assert result.cost["changes"] == 0


def test_a_fault_changes_only_the_part_of_a_running_configuration_it_has_to() -> None:
    functionalities, _ = usecase()
    base2 = functionality("robot_base2", ["base"], shareable=False, rating=20)
    sched = Scheduler([*functionalities.values(), base2])
    result = sched.schedule([move_to("1", running=True, configuration=LIDAR)], faulty={"lidar"})
    # robot_base2 is better rated, but robot_base runs and keeps running
    assert result.assignments["1"].providers == CAM


def test_the_highest_rated_provider_is_preferred() -> None:
    result = scheduler(cam_to_lidar={"rating": 30}).schedule([move_to("1")])
    assert result.assignments["1"].providers == CAM


def test_ratings_compare_per_capability_not_as_sums_over_configurations() -> None:
    # direct (rating 10, needs nothing) beats chained (8) on top of base_scan (8)
    functionalities = [
        functionality("direct", ["obstacle_scan"], rating=10),
        functionality("chained", ["obstacle_scan"], ["laser_scan"], rating=8),
        functionality("base_scan", ["laser_scan"], rating=8),
    ]
    result = Scheduler(functionalities).schedule([Request("1", "b", ("obstacle_scan",), 5.0)])
    assert result.assignments["1"].providers == {"obstacle_scan": "direct"}


def test_a_functionality_that_already_runs_is_preferred_among_equals() -> None:
    functionalities = [
        functionality("a", ["scan"], rating=5),
        functionality("b", ["scan"], rating=5),
    ]
    running = Request("1", "x", ("scan",), 50.0, running=True, configuration={"scan": "b"})
    result = Scheduler(functionalities).schedule([running, Request("2", "y", ("scan",), 5.0)])
    assert result.assignments["2"].providers == {"scan": "b"}


def test_requests_are_served_first_come_first_served() -> None:
    requests = [move_to(str(i), duration=5.0) for i in range(4)]
    result = scheduler().schedule(requests)
    assert [a.start for a in result.assignments.values()] == [0, 5, 10, 15]
    assert list(result.assignments) == ["0", "1", "2", "3"]


def test_a_later_earliest_start_lets_a_later_request_go_first() -> None:
    result = scheduler().schedule([move_to("1", earliest=30.0), move_to("2")])
    assert result.assignments["2"].start == 0
    assert result.assignments["1"].start == 30


# --- the result ----------------------------------------------------------------------------


def test_no_requests_make_an_empty_optimal_schedule() -> None:
    result = scheduler().schedule([])
    assert result.status is ScheduleStatus.OPTIMAL
    assert result.complete
    assert result.assignments == {} == result.cancelled


def test_request_ids_must_be_unique() -> None:
    with pytest.raises(ValueError, match="not unique"):
        scheduler().schedule([move_to("1"), take_picture("1")])


def test_a_request_needs_a_positive_duration() -> None:
    with pytest.raises(ValueError, match="duration must be positive"):
        move_to("1", duration=0.0)


@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(size=st.integers(1, 14), seed=st.integers(0, 10**6))
def test_every_generated_schedule_keeps_every_constraint(size: int, seed: int) -> None:
    problem = generate(size, seed)
    sched = Scheduler(problem.functionalities, time_limit=0.3)
    result = sched.schedule(problem.requests, faulty=problem.faulty)
    # the first model is a greedy schedule: never a timeout at this size
    assert result.status in (ScheduleStatus.OPTIMAL, ScheduleStatus.FEASIBLE)
    assert_valid(problem.functionalities, problem.requests, problem.faulty, result)


def test_a_time_limit_shorter_than_grounding_still_gives_the_first_schedule() -> None:
    problem = generate(60, 7)
    sched = Scheduler(problem.functionalities, time_limit=0.001)
    result = sched.schedule(problem.requests, faulty=problem.faulty)
    if result.status is ScheduleStatus.TIMEOUT:  # a very slow machine
        assert result.assignments == {}
    else:
        assert_valid(problem.functionalities, problem.requests, problem.faulty, result)


def test_the_solver_never_sees_a_tasks_id(monkeypatch: pytest.MonkeyPatch) -> None:
    """clingo keeps every symbol it made for the life of the process: a task's own id in
    the facts would grow the executive with every task ever scheduled."""
    given: list[str] = []
    add_facts = Asp.add_facts

    def seen(self: Asp, atoms: Any, **kwargs: Any) -> None:
        atoms = list(atoms)
        given.extend(str(a) for a in atoms)
        add_facts(self, atoms, **kwargs)

    monkeypatch.setattr(Asp, "add_facts", seen)
    first, then = move_to("task-4711"), move_to("task-4712", deadline=60.0)
    picture = take_picture("task-4713", together=("task-4711",))
    result = scheduler().schedule([first, then, picture])
    assert result.status is ScheduleStatus.OPTIMAL
    starts = {name: a.start for name, a in result.assignments.items()}
    assert starts == {"task-4711": 0.0, "task-4712": 10.0, "task-4713": 0.0}
    assert result.assignments["task-4712"].after == {"task-4711"}
    assert given
    assert not [fact for fact in given if "task-47" in fact]
