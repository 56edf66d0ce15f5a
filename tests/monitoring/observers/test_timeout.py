"""The timeout observer: a hung publisher process, and exact loop times fed by hand."""

from __future__ import annotations

from typing import Any

from executive.bus.message import Message
from executive.bus.payloads import GENERAL_OK, TIMEOUT
from monitoring.observer import Observer, make_observer
from monitoring.observer_config import config_of
from monitoring.observer_manager import ObserverManager
from tests.monitoring.harness import Observations, Publish, seen, stream


def timeout_observer(timeout: float, **settings: Any) -> dict[str, Any]:
    return {
        "type": "timeout",
        "topics": [
            {"name": "scan", "callerids": [{"callerid": [], "timeout": timeout, **settings}]}
        ],
    }


def started(config: dict[str, Any], now: float = 0.0) -> Observer:
    observer = make_observer(config_of(config))
    observer.start(now)
    return observer


def message(received: float, caller: str = "lidar") -> Message:
    return Message("topic/scan", b"{}", caller, None, received)


def test_a_hung_publisher_is_reported_after_the_timeout(
    manager: ObserverManager, observations: Observations, publish: Publish
) -> None:
    publish("lidar", [stream("topic/scan", {"rate": 50, "duration": 1.0})])
    manager.add(timeout_observer(0.3))
    ok = observations.next(seen("timeout", ["scan"], GENERAL_OK))
    assert ok["values"]["silence"] <= 0.3
    hung = observations.next(seen("timeout", ["scan"], TIMEOUT))
    assert hung["observation_msg"] == "timeout"
    assert hung["verbose_observation_msg"].startswith("no message for")


def test_a_hang_is_reported_at_the_first_loop_after_the_timeout() -> None:
    observer = started(timeout_observer(0.5))
    assert observer.period == 0.125  # the default: four loops per timeout
    [(_, handler)] = observer.inputs()
    handler(message(1.0))
    ticks = [1.0 + observer.period * k for k in range(1, 8)]
    codes = [observer.observe(t)[0].info.observation for t in ticks]
    assert codes == [GENERAL_OK] * 4 + [TIMEOUT] * 3
    first = ticks[codes.index(TIMEOUT)]
    assert first - 1.0 <= 0.5 + observer.period


def test_after_max_timeouts_in_a_row_the_observer_is_quiet_until_a_message_comes() -> None:
    observer = started(timeout_observer(1.0, max_timeouts_in_a_row=2))
    [(_, handler)] = observer.inputs()
    handler(message(0.0))
    assert [r.info.observation for r in observer.observe(1.5)] == [TIMEOUT]
    assert [r.info.observation for r in observer.observe(2.5)] == [TIMEOUT]
    assert observer.observe(3.5) == []
    handler(message(3.6))
    assert [r.info.observation for r in observer.observe(3.7)] == [GENERAL_OK]


def test_a_silence_longer_than_its_limit_by_the_first_report_is_reported_once() -> None:
    # the publisher stopped during the start-up time; the first loop comes after
    # max_timeouts_in_a_row timeouts: the silence is reported, then the observer is quiet
    observer = started(timeout_observer(0.5, max_timeouts_in_a_row=2))
    [(_, handler)] = observer.inputs()
    handler(message(0.1))
    [first] = observer.observe(2.0)
    assert first.info.observation == TIMEOUT
    assert observer.observe(2.125) == []
    handler(message(3.0))
    assert [r.info.observation for r in observer.observe(3.1)] == [GENERAL_OK]
    [again] = observer.observe(5.0)  # a new silence: reported again
    assert again.info.observation == TIMEOUT


def test_silence_from_the_start_counts_as_a_timeout() -> None:
    observer = started(timeout_observer(1.0), now=10.0)
    assert [r.info.observation for r in observer.observe(10.9)] == [GENERAL_OK]
    [late] = observer.observe(11.2)
    assert late.info.observation == TIMEOUT
    assert "since the start" in late.info.verbose_observation_msg


def test_a_caller_id_group_times_out_while_another_publisher_goes_on() -> None:
    config = {
        "type": "timeout",
        "topics": [
            {
                "name": "scan",
                "callerids": [
                    {"callerid": [], "timeout": 1.0},
                    {"callerid": ["lidar"], "timeout": 1.0},
                ],
            }
        ],
    }
    observer = started(config)
    [(_, handler)] = observer.inputs()
    handler(message(0.5, "lidar"))
    handler(message(1.9, "other"))
    results = {r.info.callerids: r.info.observation for r in observer.observe(2.0)}
    assert results == {(): GENERAL_OK, ("lidar",): TIMEOUT}
