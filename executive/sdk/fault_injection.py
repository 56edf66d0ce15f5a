"""Fault injection: make a component misbehave on purpose, for tests and benchmarks.

A fault comes from the component's parameters, active from its start (``params:
{fault: crash}`` or ``{fault: {mode: wrong_rate, factor: 0.5, after: 2}}``), or from an
``inject_fault`` command at run time (``{"cmd": "inject_fault", "fault": ...}``). The
SDK carries out the generic modes itself; what ``out_of_range`` and ``slip`` mean is up
to each component, which asks :meth:`FaultInjector.active`.
"""

from __future__ import annotations

import enum
import logging
import os
import sys
import threading
import time
from collections.abc import Callable, Mapping
from dataclasses import dataclass, fields
from typing import Any

from executive.bus.clock import Clock, system_clock
from knowledge.errors import ComponentError

log = logging.getLogger("dura.faults")

CRASH_DELAY = 0.05  # seconds: a crash on command comes after the command's answer


class FaultMode(enum.Enum):
    CRASH = "crash"  # exit at once with exit_code
    HANG = "hang"  # stop responding: no commands, no output, SIGTERM ignored
    STOP_PUBLISHING = "stop_publishing"  # publish nothing
    WRONG_RATE = "wrong_rate"  # rate loops run at factor x their rate
    STALE_TIMESTAMPS = "stale_timestamps"  # published stamps lag by age seconds
    OUT_OF_RANGE = "out_of_range"  # the component publishes impossible values
    HIGH_CPU = "high_cpu"  # a thread spins on a core
    GROWING_MEMORY = "growing_memory"  # allocate mb_per_s MiB every second, up to limit_mb
    SLIP = "slip"  # odometry and IMU disagree (robot_base)
    NONE = "none"  # clear every fault


@dataclass(frozen=True)
class Fault:
    """One fault to inject, with the options of its mode."""

    mode: FaultMode
    after: float = 0.0  # seconds from injection (or start) until it strikes
    factor: float = 0.5
    age: float = 5.0
    exit_code: int = 1
    mb_per_s: float = 20.0
    limit_mb: float = 512.0

    @classmethod
    def parse(cls, spec: object) -> Fault:
        """A fault from ``"crash"`` or ``{"mode": "crash", "after": 1.0, ...}``.

        Raises:
            ComponentError: an unknown mode or option, or an option of the wrong type.
        """
        options: dict[str, Any] = {}
        if isinstance(spec, Mapping):
            options = dict(spec)
            spec = options.pop("mode", None)
        modes = ", ".join(m.value for m in FaultMode)
        try:
            mode = FaultMode(spec)
        except ValueError:
            raise ComponentError(f"unknown fault mode {spec!r} (choose from {modes})") from None
        known = {f.name: f for f in fields(cls) if f.name != "mode"}
        values: dict[str, Any] = {}
        for key, value in options.items():
            if key not in known:
                raise ComponentError(
                    f"unknown option {key!r} for fault {mode.value!r} (options: {', '.join(known)})"
                )
            kind = int if key == "exit_code" else float
            if isinstance(value, bool) or not isinstance(value, (int, float)):
                raise ComponentError(f"fault option {key!r} must be a number, not {value!r}")
            values[key] = kind(value)
        return cls(mode, **values)


class FaultInjector:
    """The faults a component currently suffers, and the effects the SDK applies.

    Args:
        on_hang: called (on any thread) to make the component stop responding.
    """

    def __init__(self, on_hang: Callable[[], None], clock: Clock | None = None) -> None:
        self._on_hang = on_hang
        self._clock = clock or system_clock()
        self._active: dict[FaultMode, Fault] = {}
        self._lock = threading.Lock()
        self._ballast: list[bytes] = []

    def inject(self, fault: Fault) -> None:
        """Make a fault strike now, or after ``fault.after`` seconds (robot time)."""
        after = self._clock.wall(fault.after)
        delay = max(after, CRASH_DELAY if fault.mode is FaultMode.CRASH else 0.0)
        if delay > 0:
            timer = threading.Timer(delay, self._strike, (fault,))
            timer.daemon = True
            timer.start()
        else:
            self._strike(fault)

    def _strike(self, fault: Fault) -> None:
        log.warning("injected fault: %s", fault.mode.value)
        if fault.mode is FaultMode.NONE:
            with self._lock:
                self._active.clear()
                self._ballast.clear()
            return
        if fault.mode is FaultMode.CRASH:
            sys.stderr.flush()
            os._exit(fault.exit_code)
        with self._lock:
            self._active[fault.mode] = fault
        if fault.mode is FaultMode.HANG:
            self._on_hang()
        elif fault.mode is FaultMode.HIGH_CPU:
            threading.Thread(target=self._spin, daemon=True, name="fault-cpu").start()
        elif fault.mode is FaultMode.GROWING_MEMORY:
            threading.Thread(target=self._grow, args=(fault,), daemon=True).start()

    def active(self, mode: FaultMode) -> bool:
        return mode in self._active

    @property
    def silent(self) -> bool:
        """Whether publications are to be dropped."""
        return FaultMode.STOP_PUBLISHING in self._active or FaultMode.HANG in self._active

    def rate_factor(self) -> float:
        fault = self._active.get(FaultMode.WRONG_RATE)
        return fault.factor if fault is not None and fault.factor > 0 else 1.0

    def stamp(self, stamp: float) -> float:
        fault = self._active.get(FaultMode.STALE_TIMESTAMPS)
        return stamp - self._clock.wall(fault.age) if fault is not None else stamp

    def _spin(self) -> None:
        while FaultMode.HIGH_CPU in self._active:
            for _ in range(10_000):
                pass

    def _grow(self, fault: Fault) -> None:
        chunk = int(fault.mb_per_s * (1 << 20) / 10)
        while FaultMode.GROWING_MEMORY in self._active:
            if len(self._ballast) * chunk < fault.limit_mb * (1 << 20):
                self._ballast.append(b"x" * chunk)  # written, so resident
            time.sleep(0.1)
