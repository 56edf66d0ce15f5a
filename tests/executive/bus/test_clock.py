"""Robot time: DURA_TIME_SCALE read once, checked, and handed to child processes."""

from __future__ import annotations

import threading

import pytest

from executive.bus.clock import SCALE_VARIABLE, Clock
from knowledge.errors import ConfigError


def test_without_the_variable_robot_time_is_wall_time() -> None:
    clock = Clock.from_environment({})
    assert clock.scale == 1.0 and not clock.scaled
    assert clock.wall(7.5) == 7.5
    assert clock.environment() == {}


def test_a_scale_of_ten_makes_robot_seconds_a_tenth_of_a_wall_second() -> None:
    clock = Clock.from_environment({SCALE_VARIABLE: "10"})
    assert clock.scaled
    assert clock.wall(76.0) == pytest.approx(7.6)
    assert clock.robot(0.5) == pytest.approx(5.0)
    assert clock.environment() == {SCALE_VARIABLE: "10.0"}


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("fast", r"^DURA_TIME_SCALE='fast': the time scale must be a positive number$"),
        ("0", r"^the time scale must be positive, not 0$"),
        ("-2", r"^the time scale must be positive, not -2$"),
        ("inf", r"^the time scale must be a number, not inf$"),
    ],
)
def test_a_bad_time_scale_is_refused_with_the_reason(text: str, message: str) -> None:
    with pytest.raises(ConfigError, match=message):
        Clock.from_environment({SCALE_VARIABLE: text})


def test_a_timer_fires_after_its_robot_time_on_the_scaled_clock() -> None:
    fired = threading.Event()
    Clock(1000.0).timer(5.0, fired.set)  # 5 ms of wall time
    assert fired.wait(5.0)
