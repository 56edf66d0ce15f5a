"""The offline replay: the use-case robot's real observers, diagnosis (clingo) and repair
rules driven by scripted messages, with the messages' time as the clock."""

from __future__ import annotations

import dataclasses
import json
from collections.abc import Iterator

import pytest

from executive.bus.keys import component, topic
from executive.bus.message import Message
from executive.bus.payloads import ComponentState
from executive.bus.states import Lifecycle
from knowledge.description import RobotDescription
from knowledge.robot import load_robot
from monitoring.replay import Replay
from monitoring.timeline import DiagnosisEntry, RepairEntry, Timeline
from tests.conftest import USECASE

T0 = 1_700_000_000.0  # the recording's clock: seconds since the epoch


@pytest.fixture(scope="module")
def robot() -> RobotDescription:
    return load_robot(USECASE)


def scans(begin: float, end: float, caller: str = "lidar") -> Iterator[Message]:
    """lidar's scan at 10 Hz from ``begin`` to before ``end`` (seconds after T0)."""
    for k in range(round(begin * 10), round(end * 10)):
        t = T0 + k / 10
        yield Message(topic("scan"), json.dumps({"stamp": t}).encode(), caller, t, t)


def gap_of_two_seconds() -> list[Message]:
    return [*scans(0.0, 10.0), *scans(12.0, 20.0)]


def replay(robot: RobotDescription, messages: list[Message], **options: object) -> Timeline:
    keys = {m.key for m in messages}
    origin = messages[0].received_ns
    return Replay(robot, provided=keys, origin_ns=origin, **options).run(messages)  # type: ignore[arg-type]


def test_a_two_second_gap_in_the_scan_is_seen_diagnosed_and_repaired_at_the_recorded_times(
    robot: RobotDescription,
) -> None:
    timeline = replay(robot, gap_of_two_seconds())
    changes = [(e.time, e.observer, e.info.observation_msg) for e in timeline.observations()]
    assert changes == [
        (2.0, "lidar/0", "ok"),
        (2.0, "lidar/1", "ok"),
        (10.5, "lidar/0", "stopped"),  # 0.6 s after the last scan, at the frequency loop
        (10.5, "lidar/1", "timeout"),  # the first 8 Hz loop after 0.5 s of silence
        (12.125, "lidar/1", "ok"),
        (12.5, "lidar/0", "ok"),
    ]
    assert timeline.diagnoses() == [
        DiagnosisEntry(10.52, "DIAGNOSED", (("lidar",),), ("frequency[scan]", "timeout[scan]")),
        DiagnosisEntry(12.52, "OK"),
    ]
    assert timeline.repairs() == [RepairEntry(10.52, "restart_lidar", "restart lidar", ("lidar",))]
    (hold,) = timeline.holds()
    assert (hold.diagnosis, hold.periods, hold.held_at_end) == (
        ("lidar",),
        ((10.52, 12.52),),
        False,
    )
    assert hold.total == 2.0
    assert (timeline.begin, timeline.end, timeline.messages) == (0.0, 19.9, 180)


def test_replaying_the_same_messages_twice_gives_the_same_timeline(
    robot: RobotDescription,
) -> None:
    first = replay(robot, gap_of_two_seconds())
    second = replay(robot, gap_of_two_seconds())
    assert first == second
    assert json.dumps(first.to_payload()) == json.dumps(second.to_payload())


def test_a_rule_with_a_recall_duration_fires_again_while_the_diagnosis_holds(
    robot: RobotDescription,
) -> None:
    timeline = replay(robot, [*scans(0.0, 10.0), *scans(20.0, 22.0)])
    assert [r.time for r in timeline.repairs()] == [10.52, 15.52]  # recall_duration 5 s
    assert timeline.holds()[0].periods == ((10.52, 20.52),)


def test_a_diagnosis_still_held_at_the_end_is_held_until_the_end(robot: RobotDescription) -> None:
    messages = [*scans(0.0, 10.0), *scans(13.0, 13.1)]
    (hold,) = replay(robot, messages).holds()
    assert hold.held_at_end and hold.periods == ((10.52, 13.0),)


def test_observers_start_at_the_start_of_the_window(robot: RobotDescription) -> None:
    messages = gap_of_two_seconds()
    timeline = replay(robot, messages, start_ns=round((T0 + 5.0) * 1e9))
    assert timeline.observations()[0].time == 7.0  # 2 s start-up after the window's start
    assert timeline.begin == 5.0 and timeline.messages == 130


def test_an_observer_whose_topic_was_not_recorded_is_skipped_with_the_reason(
    robot: RobotDescription,
) -> None:
    messages = [
        Message(topic("odom"), b"{}", "robot_base", T0 + k / 10, T0 + k / 10) for k in range(10)
    ]
    timeline = replay(robot, messages)
    assert timeline.skipped == (
        "lidar/0 (frequency): no scan recorded",
        "lidar/1 (timeout): no scan recorded",
    )
    assert timeline.entries == ()


def state(name: str, lifecycle: Lifecycle, t: float) -> Message:
    payload = ComponentState(name, lifecycle, stamp=t).to_payload()
    return Message(component(name, "state"), json.dumps(payload).encode(), "executive", t, t)


def test_with_component_states_observers_run_only_while_their_component_is_ready(
    robot: RobotDescription,
) -> None:
    messages = [
        state("lidar", Lifecycle.READY, T0),
        *scans(0.0, 5.0),
        state("lidar", Lifecycle.STOPPING, T0 + 5.0),
        state("lidar", Lifecycle.STOPPED, T0 + 5.01),
        state("lidar", Lifecycle.READY, T0 + 6.0),
        *scans(6.0, 9.0),
    ]
    timeline = replay(robot, messages)
    assert [(s.time, s.state) for s in timeline.states()] == [
        (0.0, "ready"),
        (5.0, "stopping"),
        (5.01, "stopped"),
        (6.0, "ready"),
    ]
    observed = [(e.time, e.observer, e.info.observation_msg) for e in timeline.observations()]
    assert observed == [
        (2.0, "lidar/0", "ok"),
        (2.0, "lidar/1", "ok"),
        (8.0, "lidar/0", "ok"),  # afresh: start-up time again after it became ready
        (8.0, "lidar/1", "ok"),
    ]
    assert timeline.diagnoses() == []  # a stopped component is no fault


def test_observers_loop_when_the_live_run_says_they_did(robot: RobotDescription) -> None:
    # the live timeout observer (8 Hz) looped 40 ms off the replay's own phase
    live = [2.04 + k / 8 for k in range(150)]
    loops = {"lidar/1": [round((T0 + t) * 1e9) for t in live]}
    timeline = replay(robot, gap_of_two_seconds(), loops=loops)
    timeouts = [(e.time, e.info.observation_msg) for e in timeline.observations("lidar/1")]
    assert timeouts == [(2.04, "ok"), (10.415, "timeout"), (12.04, "ok")]  # live loops only
    own = [(e.time, e.info.observation_msg) for e in replay(robot, gap_of_two_seconds())
           .observations("lidar/1")]  # fmt: skip
    assert own == [(2.0, "ok"), (10.5, "timeout"), (12.125, "ok")]


def test_the_replay_says_where_it_differs_from_the_live_run(robot: RobotDescription) -> None:
    timeline = replay(robot, gap_of_two_seconds())
    assert timeline.differences(0.125) == []  # nothing recorded: nothing to compare
    live = [
        DiagnosisEntry(10.6, "DIAGNOSED", (("lidar",),)),
        DiagnosisEntry(12.6, "OK"),
        RepairEntry(10.6, "restart_lidar", "restart lidar", ("lidar",)),
    ]
    as_live = dataclasses.replace(timeline, recorded=tuple(live))
    assert as_live.differences(0.125) == []
    assert as_live.differences(0.05) == [
        "diagnosis lidar: live 10.600-12.600, replayed 10.520-12.520",
        "rules fired: live restart_lidar at 10.600, replayed restart_lidar at 10.520",
    ]
    never = dataclasses.replace(timeline, recorded=(DiagnosisEntry(3.0, "OK"),))
    assert never.differences(0.125) == [
        "diagnosis lidar: live never, replayed 10.520-12.520",
        "rules fired: live none, replayed restart_lidar at 10.520",
    ]


def test_a_diagnosis_due_at_an_observer_loop_comes_after_it_to_the_nanosecond(
    robot: RobotDescription,
) -> None:
    # the frequency observer reports lidar stopped at 10.5 s; the diagnosis settles 10 ms
    # and is due at 10.51 s, when the live timeout observer looped too: as live, the loop
    # comes first and the diagnosis has both. In float seconds since the epoch that
    # diagnosis came 128 ns early, before the loop.
    t0_ns = 1_700_000_000 * 10**9
    loops = {"lidar/1": [t0_ns + 2_010_000_000 + k * 125_000_000 for k in range(150)]}
    timeline = replay(robot, gap_of_two_seconds(), loops=loops, settle=0.01)
    assert (10.51, "timeout") in [
        (e.time, e.info.observation_msg) for e in timeline.observations("lidar/1")
    ]
    assert timeline.diagnoses()[0] == DiagnosisEntry(
        10.51, "DIAGNOSED", (("lidar",),), ("frequency[scan]", "timeout[scan]")
    )
