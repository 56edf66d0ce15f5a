"""A behavior's goals in a real process: it waits for its inputs' first messages, and a
goal that fails in the world is told apart from a fault."""

from __future__ import annotations

import re
import threading
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

import pytest

from executive.bus.keys import topic
from executive.bus.message import Message
from executive.bus.session import Bus
from executive.bus.states import GoalStatus
from knowledge.description import ComponentSpec
from tests.executive.runtime.rig import rig, robot, scripted


def brewer(**params: object) -> ComponentSpec:
    return scripted("brewer", "tests.executive.sdk.brewer", behavior=True, params=params)


@contextmanager
def water_after(bus: Bus, delay: float) -> Iterator[None]:
    """Publish ``water`` every 50 ms from ``delay`` seconds on, until the block ends."""
    done = threading.Event()

    def pour() -> None:
        if done.wait(delay):
            return
        while not done.is_set():
            bus.publish(topic("water"), {"celsius": 93})
            done.wait(0.05)

    pourer = threading.Thread(target=pour, daemon=True)
    pourer.start()
    try:
        yield
    finally:
        done.set()
        pourer.join()


def test_a_goal_waits_for_the_first_message_of_each_watched_input(
    endpoint: str, tmp_path: Path
) -> None:
    with rig(robot(brewer()), endpoint, tmp_path) as r:
        r.launcher.start("brewer")
        handle = r.launcher.send_goal("brewer", {})  # before any water
        with water_after(r.bus, 0.5):
            result = handle.wait(15)
        assert result is not None and result.status is GoalStatus.SUCCEEDED, result
        assert result.value == {"celsius": 93}


def test_a_goal_whose_input_never_speaks_times_out_as_a_fault(
    endpoint: str, tmp_path: Path
) -> None:
    with rig(robot(brewer(timeout=0.3)), endpoint, tmp_path) as r:
        r.launcher.start("brewer")
        result = r.launcher.send_goal("brewer", {}).wait(15)
        assert result is not None and result.status is GoalStatus.FAILED
        assert result.reason == "no water yet: none came within 0.3 s"
        assert result.fault


def test_goal_failed_is_the_world_s_failure_and_an_exception_is_a_fault(
    endpoint: str, tmp_path: Path
) -> None:
    with rig(robot(brewer()), endpoint, tmp_path) as r, water_after(r.bus, 0.0):
        r.launcher.start("brewer")
        world = r.launcher.send_goal("brewer", {"world": "the cup is gone"}).wait(15)
        assert world is not None and world.status is GoalStatus.FAILED
        assert (world.reason, world.fault) == ("the cup is gone", False)
        bug = r.launcher.send_goal("brewer", {"bug": True}).wait(15)
        assert bug is not None and bug.status is GoalStatus.FAILED
        assert (bug.reason, bug.fault) == (
            "KeyError: 'no such key' (dura component logs brewer)",
            True,
        )


def test_a_message_reads_its_payload_and_a_missing_field_names_those_it_has() -> None:
    message = Message("dura/r/topic/water", b'{"celsius": 93, "stamp": 1.5}')
    assert message["celsius"] == 93 and message.get("litres") is None
    assert message.stamp == 1.5
    said = "the message on dura/r/topic/water has no field 'litres' (it has: celsius, stamp)"
    with pytest.raises(KeyError, match=re.escape(said)):
        message["litres"]
