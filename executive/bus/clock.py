"""Robot time: the seconds a robot's world runs on, possibly faster than the wall clock.

Durations in a domain, a behavior's ``sleep`` and ``work_for``, rate loops, the timeouts
of plan steps, goal deadlines and the hold times of rules are all *robot time*. In
tests and simulation the environment variable ``DURA_TIME_SCALE=N`` makes robot time
run N times faster than the wall clock, in every process of a robot at once: the
executive hands its environment to the components it starts, so a 76 s plan runs in
7.6 s with the same steps, in the same order. What is real stays real: processes
starting, bus requests and the planner's search take wall time and their timeouts are
not scaled.

A :class:`Clock` is an immutable value; :func:`system_clock` is the one this process
runs on (read from the environment once). Services take a clock as an argument and
default to it, so a unit test can hand them a fast one.
"""

from __future__ import annotations

import functools
import math
import os
import time
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING

from knowledge.errors import ConfigError

if TYPE_CHECKING:
    from executive.bus.timers import Timer

SCALE_VARIABLE = "DURA_TIME_SCALE"


@dataclass(frozen=True)
class Clock:
    """Robot time that runs ``scale`` times faster than the wall clock."""

    scale: float = 1.0

    def __post_init__(self) -> None:
        if not (isinstance(self.scale, (int, float)) and math.isfinite(self.scale)):
            raise ConfigError(f"the time scale must be a number, not {self.scale!r}")
        if self.scale <= 0:
            raise ConfigError(f"the time scale must be positive, not {self.scale:g}")

    @classmethod
    def from_environment(cls, environ: Mapping[str, str] | None = None) -> Clock:
        """Read ``DURA_TIME_SCALE`` (default 1).

        Raises:
            ConfigError: the variable is not a positive number.
        """
        text = (os.environ if environ is None else environ).get(SCALE_VARIABLE, "").strip()
        if not text:
            return cls()
        try:
            scale = float(text)
        except ValueError:
            raise ConfigError(
                f"{SCALE_VARIABLE}={text!r}: the time scale must be a positive number"
            ) from None
        return cls(scale)

    @property
    def scaled(self) -> bool:
        """Tell whether robot time runs faster (or slower) than the wall clock."""
        return self.scale != 1.0

    def wall(self, seconds: float) -> float:
        """Return the wall-clock seconds that ``seconds`` of robot time take."""
        return seconds / self.scale

    def robot(self, wall_seconds: float) -> float:
        """Return the robot seconds that ``wall_seconds`` on the wall clock are."""
        return wall_seconds * self.scale

    def monotonic(self) -> float:
        """Read a monotonic clock in robot seconds (for intervals only)."""
        return time.monotonic() * self.scale

    def sleep(self, seconds: float) -> None:
        """Sleep ``seconds`` of robot time."""
        time.sleep(max(0.0, self.wall(seconds)))

    def timer(self, seconds: float, fn: Callable[[], object]) -> Timer:
        """Call ``fn`` after ``seconds`` of robot time, on this process's timer thread
        (:mod:`.timers`: ``fn`` must be short)."""
        from executive.bus.timers import later  # only where timers are set

        return later(self.wall(seconds), fn)

    def environment(self) -> dict[str, str]:
        """Return the environment variables that give a child process this clock."""
        return {SCALE_VARIABLE: repr(float(self.scale))} if self.scaled else {}


@functools.cache
def system_clock() -> Clock:
    """Return this process's clock, read from its environment once.

    Raises:
        ConfigError: ``DURA_TIME_SCALE`` is not a positive number.
    """
    return Clock.from_environment()
