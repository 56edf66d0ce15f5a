"""The component SDK: a functionality or a behavior as a normal Python program.

    class Lidar(Functionality):
        def on_configure(self, params, achievements):
            self.rate = self.param("rate", 10.0)

        def on_start(self):
            self.at_rate(self.rate, self.scan)

        def scan(self):
            self.publish("scan", {"ranges": [1.0, 1.2]})

    if __name__ == "__main__":
        Lidar.main()

This module owns what an author sees of a component: the ``on_*`` hooks to override
and the helpers to call. The executive starts the program with the robot, the
component's name and the bus endpoint in its environment (``keys.ENV_*``);
:meth:`Component.main` connects to the bus and hands the component to its
:class:`~executive.sdk.framework.Framework`, which takes the lifecycle commands and
calls the hooks, all on the main thread. Rate loops run on threads of their own,
subscription handlers on the bus's.

The lifecycle itself is the framework's: a class that defines one of its methods
(``start``, ``stop``, ``run``, ...) is refused when it is created, with the hook to
override instead. The helpers are final (for type checkers).
"""

from __future__ import annotations

import contextlib
import logging
import os
import sys
import threading
import time
from abc import ABC, abstractmethod
from collections.abc import Callable, Mapping
from typing import Any, ClassVar, TypeVar, final

from executive.bus import keys
from executive.bus.api.components import COMPONENT_ACHIEVE, Achievement
from executive.bus.api.planning import STATE_SET, STATE_UNSET, FactChange
from executive.bus.clock import Clock, system_clock
from executive.bus.message import Message
from executive.bus.security import ENV_PASSWORD, ENV_USER, Login
from executive.bus.session import Bus
from executive.bus.states import ComponentPhase
from executive.sdk.fault_injection import FaultInjector
from executive.sdk.framework import Framework
from knowledge.description import Kind
from knowledge.errors import ComponentError, DuraError

T = TypeVar("T")

# What an author defines instead of each of the framework's methods.
FRAMEWORK_METHODS: Mapping[str, str] = {
    "configure": "on_configure",
    "start": "on_start",
    "pause": "on_pause",
    "resume": "on_resume",
    "reconfigure": "on_reconfigure",
    "stop": "on_stop",
    "run": "on_start",
    "main": "on_start",
    "run_process": "on_start",
    "take_goal": "execute",
    "cancel_goal": "execute",
}
GOAL_METHODS = ("take_goal", "cancel_goal")


def refuse_framework_methods(cls: type) -> None:
    """Refuse a component class that defines one of the framework's methods.

    Raises:
        TypeError: naming the method and the hook to override instead.
    """
    for name, hook in FRAMEWORK_METHODS.items():
        if name not in vars(cls):
            continue
        if name in GOAL_METHODS and getattr(cls, "kind", None) is not Kind.BEHAVIOR:
            raise TypeError(
                f"{cls.__name__} defines {name}(): goals are for a Behavior, which "
                f"overrides {hook}()"
            )
        raise TypeError(f"{cls.__name__} defines {name}(): override {hook}() instead")


class Component:
    """What functionalities and behaviors share: the hooks to override, the helpers.

    Override the ``on_*`` hooks (each does nothing by default); the framework calls
    them on the main thread when a lifecycle command fits the current phase.
    """

    kind: ClassVar[Kind]

    def __init_subclass__(cls, **kwargs: Any) -> None:
        super().__init_subclass__(**kwargs)
        refuse_framework_methods(cls)

    def __init__(self, name: str, bus: Bus) -> None:
        self.name = name
        self.bus = bus
        self.params: dict[str, Any] = {}
        self.achievements: dict[str, Any] = {}
        self.log = logging.getLogger(f"dura.component.{name}")
        self.clock: Clock = system_clock()  # robot time (DURA_TIME_SCALE)
        self._framework = Framework(self)
        self.faults = FaultInjector(on_hang=self._framework.hang, clock=self.clock)

    # --- hooks ------------------------------------------------------------------------

    def on_configure(self, params: dict[str, Any], achievements: dict[str, Any]) -> None:
        """Read parameters (:meth:`param`) and, for a warm start, achievements.

        Called once before the start, and again if configured twice before it.
        """

    def on_start(self) -> None:
        """Start working: rate loops (:meth:`at_rate`) and subscriptions."""

    def on_pause(self) -> None:
        """Loops and subscription handlers are already held; release what else runs."""

    def on_resume(self) -> None:
        """Take up again what :meth:`on_pause` released."""

    def on_reconfigure(self, params: dict[str, Any]) -> None:
        """React to changed parameters (already merged into :attr:`params`)."""

    def on_stop(self) -> None:
        """Release resources; loops have ended (called only if the component started)."""

    # --- helpers ----------------------------------------------------------------------

    @property
    @final
    def phase(self) -> ComponentPhase:
        return self._framework.phase

    @property
    @final
    def running(self) -> bool:
        return self._framework.running

    @property
    @final
    def ended(self) -> bool:
        return self._framework.ended

    @final
    def param(self, key: str, default: T) -> T:
        """A parameter, of the type of its default (an int is accepted for a float).

        Raises:
            ComponentError: the parameter has another type.
        """
        value = self.params.get(key, default)
        if isinstance(default, float) and isinstance(value, int) and not isinstance(value, bool):
            value = float(value)
        if default is not None and type(value) is not type(default):
            raise ComponentError(
                f"parameter {key!r} of '{self.name}' must be a {type(default).__name__}, "
                f"not {value!r}"
            )
        return value  # type: ignore[no-any-return]

    @final
    def publish(self, topic: str, payload: Mapping[str, Any]) -> None:
        """Publish on ``topic/<topic>``; ``stamp`` defaults to now. Only a topic the
        robot description lists under this component's ``publishes`` reaches anyone (the
        bus's access control drops the others)."""
        if self.faults.silent:
            return
        stamp = payload["stamp"] if "stamp" in payload else time.time()
        self.bus.publish(keys.topic(topic), {**payload, "stamp": self.faults.stamp(stamp)})

    @final
    def subscribe(self, topic: str, handler: Callable[[Message], None]) -> None:
        """Call ``handler(message)`` for each message on ``topic/<topic>`` while running (a
        topic the description lists under ``subscribes`` or opens with ``may_subscribe``;
        the bus refuses the others).

        ``message`` is a :class:`~executive.sdk.Message`: ``message.payload`` is
        the dict that was published (``message["celsius"]`` reads one field of it),
        ``message.stamp`` its ``stamp``. The handler runs on the bus's thread: keep it
        short. An exception escaping it ends the process (exit code 1), a fault.
        """

        def deliver(message: Message) -> None:
            if not self.running:
                return
            try:
                handler(message)
            except Exception:
                self._framework.fail(f"the handler of topic '{topic}'")

        self.bus.subscribe(keys.topic(topic), deliver)

    @final
    def achieve(self, key: str, value: Any) -> None:
        """Store an achievement in the KB (through the executive): it comes back in
        ``on_configure`` when the component starts again (a warm start)."""
        self.achievements[key] = value
        try:
            # best effort, and a goal's loop calls it: wait less than the verb's default
            COMPONENT_ACHIEVE.call(self.bus, Achievement(self.name, key, value), timeout=2.0)
        except DuraError as e:
            self.log.warning("achievement %r not stored: %s", key, e)

    @final
    def set_fact(self, fact: str, *, at: float | None = None) -> None:
        """Make a fact true in the robot's world (the planner's state), e.g.
        ``(battery_low)``, through the executive; with ``at`` (wall clock, seconds since
        the epoch, as :func:`time.time`), only from then on: the planner plans with it
        before (a timed fact, as ``dura state set --at``).

        Raises:
            BusError: the executive refused it (unknown predicate or object, a time in
                the past) or is gone.
        """
        STATE_SET.call(self.bus, FactChange(fact, source=self.name, at=at), timeout=5.0)

    @final
    def unset_fact(self, fact: str, *, at: float | None = None) -> None:
        """Make a fact false in the robot's world (see :meth:`set_fact`)."""
        STATE_UNSET.call(self.bus, FactChange(fact, source=self.name, at=at), timeout=5.0)

    @final
    def at_rate(self, hz: float, step: Callable[[], None]) -> Rate:
        """Call ``step`` ``hz`` times a second of robot time while running (held while
        paused): with ``DURA_TIME_SCALE=N``, N times as often on the wall clock. Returns
        the loop's :class:`Rate`, whose ``hz`` may change while it runs (in
        :meth:`on_reconfigure`).

        Deadlines are absolute, so the rate does not drift; a loop that falls more
        than a period behind (a long step, a stopped process, a pause) skips ahead
        instead of bursting: its next step comes a period after the late one
        (:func:`next_due`).
        """
        rate = Rate(hz)
        framework = self._framework

        def loop() -> None:
            due = time.monotonic()
            while framework.wait_running():
                started = time.monotonic()
                try:
                    step()
                except Exception:
                    framework.fail(f"the rate loop {getattr(step, '__name__', step)!r}")
                    return
                period = self.clock.wall(1.0 / rate.hz) / self.faults.rate_factor()
                now = time.monotonic()
                due = next_due(due, period, started, now)
                framework.wait(lambda: framework.ended, timeout=max(0.0, due - now))

        threading.Thread(target=loop, daemon=True, name=f"rate-{self.name}").start()
        return rate

    # --- the process ------------------------------------------------------------------

    @classmethod
    @final
    def main(cls) -> None:
        """Run this component as its process's program; exits with its exit code.

        The bus is closed and the output flushed when it returns; the process then ends
        at once, without Python's finalization: a rate loop's thread that is inside the
        bus's native code at that moment would otherwise be ended mid-call, which aborts
        the process (SIGABRT, "exception not rethrown") instead of a clean exit."""
        code = cls.run_process()
        logging.shutdown()
        for stream in (sys.stdout, sys.stderr):
            with contextlib.suppress(OSError, ValueError):
                stream.flush()
        os._exit(code)

    @classmethod
    @final
    def run_process(cls, *args: Any) -> int:
        """Connect to the executive named in the environment and run until stopped.

        ``args`` go to the constructor after the name and the bus.
        """
        missing = [
            v
            for v in (keys.ENV_ROBOT, keys.ENV_COMPONENT, keys.ENV_ENDPOINT)
            if not os.environ.get(v)
        ]
        if missing:
            print(
                f"{sys.argv[0]}: {', '.join(missing)} not set: components are started by the "
                "executive ('dura component start NAME')",
                file=sys.stderr,
            )
            return 2
        name = os.environ[keys.ENV_COMPONENT]
        logging.basicConfig(
            level=logging.INFO, format="%(asctime)s %(levelname)s %(name)s: %(message)s"
        )
        # the bus login is the component's alone: its own children do not inherit it
        user, password = os.environ.pop(ENV_USER, None), os.environ.pop(ENV_PASSWORD, None)
        login = Login(user, password) if user is not None and password is not None else None
        try:
            with Bus(
                os.environ[keys.ENV_ROBOT],
                name=name,
                endpoint=os.environ[keys.ENV_ENDPOINT],
                login=login,
                component=True,
            ) as bus:
                instance = os.environ.get(keys.ENV_INSTANCE) or str(os.getpid())
                return cls(name, bus, *args)._framework.run(instance)
        except DuraError as e:
            logging.getLogger(f"dura.component.{name}").error("%s", e)
            return 1


def next_due(due: float, period: float, started: float, now: float) -> float:
    """When a rate loop's next step is due, ``now`` that the step due at ``due``, which
    ``started`` then, is done.

    On time, or less than a period late: a ``period`` after ``due`` (absolute deadlines:
    the loop catches up and does not drift). Started more than a period late (the
    process was stopped, or held up): a period after it started, so that the next step
    does not follow at once, a burst whose one short period a frequency observer would
    read as a rate far too high. A step that itself took more than two periods is
    followed at once.
    """
    if started - due > period:
        return started + period
    due += period
    return now if due < now - period else due


class Rate:
    """The rate of a loop :meth:`Component.at_rate` runs, in Hz; set ``hz`` to change it
    (from the next period on).

    Raises:
        ComponentError: a rate that is not a positive number.
    """

    def __init__(self, hz: float) -> None:
        self.hz = hz

    @property
    def hz(self) -> float:
        return self._hz

    @hz.setter
    def hz(self, value: float) -> None:
        if isinstance(value, bool) or not isinstance(value, int | float) or not value > 0:
            raise ComponentError(f"a rate must be a positive number, not {value!r}")
        self._hz = float(value)


class Functionality(Component, ABC):
    """A component that runs until it is stopped and provides capabilities."""

    kind = Kind.FUNCTIONALITY

    @abstractmethod
    def on_start(self) -> None:
        """Start publishing: rate loops (:meth:`at_rate`) and subscriptions."""
