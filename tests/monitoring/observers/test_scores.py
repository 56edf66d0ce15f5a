"""The scores observer: a number inside the payload, named by a field path."""

from __future__ import annotations

import pytest

from executive.bus.message import Message
from executive.bus.payloads import GENERAL_ERROR
from monitoring.observer import make_observer
from monitoring.observer_config import config_of
from monitoring.observer_manager import ObserverManager
from tests.monitoring.harness import Observations, Publish, seen, stream

SCORES = {
    "type": "value",
    "main_loop_rate": 5.0,
    "topics": [
        {
            "name": "battery",
            "field": "charge.cells.1",
            "filter": {"type": "mean", "window_size": 3},
            "states": [
                {
                    "state": "charged",
                    "number": 1,
                    "score": {"type": "greater_than", "greater_than": 20},
                },
                {"state": "low", "number": -7, "score": {"type": "less_than", "less_than": 20}},
            ],
        }
    ],
}


def test_a_draining_battery_goes_from_charged_to_low(
    manager: ObserverManager, observations: Observations, publish: Publish
) -> None:
    full = {"charge": {"cells": [0, 80]}}
    empty = {"charge": {"cells": [99, 10]}}
    publish(
        "battery_driver",
        [
            stream(
                "topic/battery",
                {"rate": 10, "duration": 1.5, "payload": full},
                {"rate": 10, "payload": empty},
            )
        ],
    )
    manager.add(SCORES)
    charged = observations.next(seen("scores", ["battery"], 1))
    assert charged["values"]["score"] == pytest.approx(80)
    low = observations.next(seen("scores", ["battery"], -7))
    assert low["values"]["score"] == pytest.approx(10)


def test_messages_without_the_field_are_an_error_until_a_value_comes() -> None:
    observer = make_observer(config_of(SCORES))
    observer.start(0.0)
    [(key, handler)] = observer.inputs()
    handler(Message(key, b'{"charge": {"cells": [1]}}', "b", None, 1.0))
    [missing] = observer.observe(1.5)
    assert missing.info.observation == GENERAL_ERROR
    assert "at 'charge.cells.1'" in missing.info.verbose_observation_msg
    handler(Message(key, b'{"charge": {"cells": [1, 50]}}', "b", None, 2.0))
    [found] = observer.observe(2.5)
    assert found.info.observation == 1 and found.values == {"score": 50.0}
