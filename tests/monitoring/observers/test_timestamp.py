"""The timestamp observer: a publisher whose stamps fall behind."""

from __future__ import annotations

from executive.bus.message import Message
from executive.bus.payloads import GENERAL_ERROR
from monitoring.observer import make_observer
from monitoring.observer_config import config_of
from monitoring.observer_manager import ObserverManager
from tests.monitoring.harness import Observations, Publish, seen, stream

TIMESTAMP = {
    "type": "timestamp",
    "main_loop_rate": 5.0,
    "topics": [
        {
            "name": "scan",
            "filter": {"type": "median", "window_size": 5},
            "states": [
                {"state": "fresh", "number": 1, "age": {"type": "less_than", "less_than": 0.3}},
                {
                    "state": "stale",
                    "number": -6,
                    "age": {"type": "greater_than", "greater_than": 0.3},
                },
            ],
        }
    ],
}


def test_stale_stamps_are_reported(
    manager: ObserverManager, observations: Observations, publish: Publish
) -> None:
    publish(
        "lidar",
        [stream("topic/scan", {"rate": 20, "duration": 1.5}, {"rate": 20, "stamp_age": 1.0})],
    )
    manager.add(TIMESTAMP)
    fresh = observations.next(seen("timestamp", ["scan"], 1))
    assert 0.0 <= fresh["values"]["age"] < 0.3
    stale = observations.next(seen("timestamp", ["scan"], -6))
    assert stale["observation_msg"] == "stale" and stale["values"]["age"] >= 1.0


def test_messages_without_a_stamp_are_an_error() -> None:
    observer = make_observer(config_of(TIMESTAMP))
    observer.start(0.0)
    [(key, handler)] = observer.inputs()
    handler(Message(key, b'{"data": 1}', "lidar", None, 1.0))
    handler(Message(key, b"not json", "lidar", None, 1.1))
    [result] = observer.observe(2.0)
    assert result.info.observation == GENERAL_ERROR
    assert result.info.verbose_observation_msg == "2 messages without a numeric 'stamp'"
