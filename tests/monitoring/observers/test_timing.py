"""The timing observer: a publisher that answers each message after a delay, and the
two ways of pairing messages, fed by hand."""

from __future__ import annotations

from typing import Any

import pytest

from executive.bus.message import Message
from executive.bus.payloads import NO_STATE_FITS
from monitoring.observer import make_observer
from monitoring.observer_config import config_of
from monitoring.observer_manager import ObserverManager
from tests.monitoring.harness import Observations, Publish, seen, stream


def timing(single_shot: bool = False, rate: float = 5.0) -> dict[str, Any]:
    return {
        "type": "timing",
        "main_loop_rate": rate,
        "use_global_subscriber": True,
        "topics": [
            {
                "topicA": "scan",
                "calleridA": [],
                "topicB": "scan_filtered",
                "calleridB": [],
                "single_shot_mode": single_shot,
                "filter": {"type": "mean", "window_size": 5},
                "states": [
                    {"state": "ok", "number": 1, "delay": {"type": "less_than", "less_than": 0.1}}
                ],
            }
        ],
    }


def test_a_component_that_answers_late_leaves_its_state(
    manager: ObserverManager, observations: Observations, publish: Publish
) -> None:
    echo = {"key": "topic/scan_filtered"}
    publish(
        "lidar_filter",
        [
            stream(
                "topic/scan",
                {"rate": 5, "duration": 2.0, "echo": {**echo, "delay": 0.02}},
                {"rate": 2, "echo": {**echo, "delay": 0.3}},
            )
        ],
    )
    manager.add(timing())
    ok = observations.next(seen("timing", ["scan", "scan_filtered"], 1))
    assert 0.0 < ok["values"]["delay"] < 0.1
    late = observations.next(seen("timing", ["scan", "scan_filtered"], NO_STATE_FITS))
    assert late["values"]["delay"] >= 0.1


def delays(single_shot: bool, events: list[tuple[str, float]]) -> float:
    """The mean measured delay of A and B messages at the given times."""
    observer = make_observer(config_of(timing(single_shot)))
    observer.start(0.0)
    handlers = {key: handler for key, handler in observer.inputs()}
    for topic, received in events:
        key = "topic/scan" if topic == "A" else "topic/scan_filtered"
        handlers[key](Message(key, b"{}", "x", None, received))
    [result] = observer.observe(10.0)
    return result.values["delay"]


EVENTS = [("B", 0.0), ("A", 1.0), ("A", 1.5), ("B", 1.6), ("B", 1.7), ("A", 2.0), ("B", 2.25)]


def test_periodic_pairing_measures_from_the_first_message_on_a() -> None:
    # 1.0 -> 1.6 and 2.0 -> 2.25
    assert delays(False, EVENTS) == pytest.approx((0.6 + 0.25) / 2)


def test_single_shot_pairing_measures_the_closest_pair() -> None:
    # 1.5 -> 1.6 and 2.0 -> 2.25; the second B at 1.7 has no A of its own
    assert delays(True, EVENTS) == pytest.approx((0.1 + 0.25) / 2)
