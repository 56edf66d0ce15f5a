"""The frequency observer: real publisher processes, and exact periods fed by hand."""

from __future__ import annotations

from typing import Any

import pytest

from executive.bus.message import Message
from executive.bus.payloads import NO_STATE_FITS, TIMEOUT
from monitoring.observer import make_observer
from monitoring.observer_config import config_of
from monitoring.observer_manager import ObserverManager
from tests.monitoring.harness import Observations, Publish, seen, stream


def frequency(
    groups: list[dict[str, Any]], rate: float = 5.0, start_up: float = 0.5
) -> dict[str, Any]:
    return {
        "type": "frequency",
        "main_loop_rate": rate,
        "start_up_time": start_up,
        "topics": [{"name": "scan", "callerids": groups}],
    }


def group(callerids: list[str], low: float, high: float, **extra: Any) -> dict[str, Any]:
    return {
        "callerid": callerids,
        "filter": {"type": "mean", "window_size": 10},
        "states": [
            {
                "state": "ok",
                "number": 1,
                "frequency": {"type": "in_between", "lower_bound": low, "upper_bound": high},
            },
            {"state": "slow", "number": -5, "frequency": {"type": "less_than", "less_than": low}},
        ],
        **extra,
    }


def test_a_steady_topic_is_in_its_state_with_its_frequency(
    manager: ObserverManager, observations: Observations, publish: Publish
) -> None:
    publish("lidar", [stream("topic/scan", {"rate": 50})])
    manager.add(frequency([group([], 40, 60)]))
    found = observations.next(seen("frequency", ["scan"], 1))
    assert found["observation_msg"] == "ok"
    assert 40 <= found["values"]["frequency"] <= 60


def test_a_slow_topic_is_told_from_a_stopped_one(
    manager: ObserverManager, observations: Observations, publish: Publish
) -> None:
    publish(
        "lidar",
        [stream("topic/scan", {"rate": 50, "duration": 1.5}, {"rate": 20, "duration": 2.0})],
    )
    manager.add(frequency([group([], 40, 60)]))
    observations.next(seen("frequency", ["scan"], 1))
    slow = observations.next(seen("frequency", ["scan"], -5))
    assert slow["observation_msg"] == "slow" and slow["values"]["frequency"] < 40
    stopped = observations.next(seen("frequency", ["scan"], TIMEOUT))
    assert stopped["observation_msg"] == "stopped"
    assert stopped["verbose_observation_msg"].startswith("stopped: no message for")


def test_a_topic_slower_than_the_loop_is_not_stopped_between_its_messages(
    manager: ObserverManager, observations: Observations, publish: Publish
) -> None:
    publish("lidar", [stream("topic/scan", {"rate": 2})])
    manager.add(frequency([group([], 1.5, 2.5)], rate=10.0, start_up=1.2))
    observations.next(seen("frequency", ["scan"]))
    reports = [o for o in observations.during(2.5) if o["type"] == "frequency"]
    assert len(reports) >= 15
    assert {o["observation"] for o in reports} == {1}, reports


def test_a_caller_id_group_isolates_one_of_two_publishers(
    manager: ObserverManager, observations: Observations, publish: Publish
) -> None:
    publish("lidar", [stream("topic/scan", {"rate": 50})])
    publish("other", [stream("topic/scan", {"rate": 20})])
    manager.add(frequency([group([], 60, 80), group(["lidar"], 40, 60), group(["other"], 15, 25)]))
    for callerids, low, high in (([], 60, 80), (["lidar"], 40, 60), (["other"], 15, 25)):
        found = observations.next(seen("frequency", ["scan"], 1, callerids))
        assert low <= found["values"]["frequency"] <= high


def arrivals(caller: str, start: float, rate: float, count: int) -> list[Message]:
    return [Message("topic/scan", b"{}", caller, None, start + i / rate) for i in range(count)]


def test_a_gap_after_a_stop_is_no_period_once_messages_come_back() -> None:
    config = config_of(frequency([group([], 9, 11)], rate=1.0, start_up=0.0))
    observer = make_observer(config)
    observer.start(0.0)
    [(_, handler)] = observer.inputs()
    for message in arrivals("lidar", 0.0, 10, 20):
        handler(message)
    [before] = observer.observe(2.0)
    assert before.info.observation == 1
    [stopped] = observer.observe(5.0)
    assert stopped.info.observation == TIMEOUT
    for message in arrivals("lidar", 10.0, 10, 30):
        handler(message)
    [after] = observer.observe(13.0)
    assert after.info.observation == 1
    assert after.values["frequency"] == pytest.approx(10.0)


def test_a_topic_that_never_publishes_is_stopped_after_the_start_up() -> None:
    config = config_of(frequency([group([], 9, 11)], rate=2.0, start_up=1.5))
    observer = make_observer(config)
    observer.start(100.0)
    assert observer.observe(101.5) == []
    [stopped] = observer.observe(101.6)
    assert stopped.info.observation == TIMEOUT
    assert "since the start" in stopped.info.verbose_observation_msg


def test_a_publisher_that_stops_after_its_first_message_is_stopped_after_the_start_up() -> None:
    config = config_of(frequency([group([], 9, 11)], rate=2.0, start_up=1.5))
    observer = make_observer(config)
    observer.start(100.0)
    [(_, handler)] = observer.inputs()
    handler(Message("topic/scan", b"{}", "lidar", None, 100.1))  # one message, no period
    assert observer.observe(101.5) == []  # its rate is not known yet
    [stopped] = observer.observe(101.7)
    assert stopped.info.observation == TIMEOUT
    assert stopped.info.verbose_observation_msg.startswith("stopped: no message for")


def test_a_slow_publishers_first_period_counts_however_long() -> None:
    config = config_of(frequency([group([], 0.15, 0.25)], rate=2.0, start_up=1.5))
    observer = make_observer(config)
    observer.start(0.0)
    [(_, handler)] = observer.inputs()
    first, second = arrivals("beacon", 0.0, 0.2, 2)  # every 5 s
    handler(first)
    assert observer.observe(1.0) == []  # its rate is not known yet
    handler(second)
    [slow] = observer.observe(5.1)
    assert slow.info.observation == 1  # the first period is one, not a gap
    assert slow.values["frequency"] == pytest.approx(0.2)


def test_no_state_fits_a_frequency_between_the_states() -> None:
    config = config_of(
        frequency(
            [
                {
                    "callerid": [],
                    "filter": {"type": "mean", "window_size": 5},
                    "states": [
                        {
                            "state": "ok",
                            "number": 1,
                            "frequency": {"type": "greater_than", "greater_than": 20},
                        }
                    ],
                }
            ],
            start_up=0.0,
        )
    )
    observer = make_observer(config)
    observer.start(0.0)
    [(_, handler)] = observer.inputs()
    for message in arrivals("lidar", 0.0, 10, 6):
        handler(message)
    [result] = observer.observe(0.6)
    assert result.info.observation == NO_STATE_FITS
    assert result.values["frequency"] == pytest.approx(10.0)
    assert "fits none of: ok: frequency > 20" in result.info.verbose_observation_msg
