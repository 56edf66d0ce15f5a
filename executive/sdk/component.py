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

The executive starts the program with the robot, the component's name and the bus
endpoint in its environment (``keys.ENV_*``). :meth:`Component.main` connects to
the bus, takes lifecycle commands on ``component/<name>/cmd`` and runs every lifecycle
hook on the main thread; rate loops run on threads of their own, subscription handlers
on the bus's. The process ends with exit code 0 when it is stopped (a command, SIGTERM
or SIGINT, or the executive's liveliness token vanishing) and with 1 when an exception
escapes a loop or a handler.
"""

from __future__ import annotations

import json
import logging
import os
import queue
import signal
import sys
import threading
import time
from abc import ABC, abstractmethod
from collections.abc import Callable, Mapping
from concurrent.futures import Future
from typing import Any, ClassVar, TypeVar

from executive.bus import keys
from executive.bus.payloads import Command, ComponentPhase, GoalResult, GoalStatus
from executive.bus.session import Bus, Message
from executive.sdk.fault_injection import Fault, FaultInjector
from knowledge.description import Kind
from knowledge.errors import BusError, ComponentError, DuraError

T = TypeVar("T")

# After the executive vanished, a component that has not ended by then is ended hard.
EXECUTIVE_GONE_DEADLINE = 1.5
# How long stop waits for a running goal to publish its (cancelled) result.
GOAL_STOP_TIMEOUT = 2.0
WAIT_STEP = 0.05  # seconds between two looks of Behavior.wait_until


class GoalFailed(Exception):
    """Raise in :meth:`Behavior.execute` to fail the goal; the message is the reason."""


class GoalCancelled(Exception):
    """Raised by :meth:`Behavior.checkpoint` once the goal is cancelled or stopped."""


def _object(request: Mapping[str, Any], key: str) -> dict[str, Any]:
    value = request.get(key) or {}
    if not isinstance(value, dict):
        raise ComponentError(f"'{key}' must be an object, not {json.dumps(value)}")
    return value


class Component:
    """What functionalities and behaviors share: lifecycle, bus helpers, parameters.

    Override the ``on_*`` hooks; the public lifecycle methods check that the command
    fits the current phase and then call them.
    """

    kind: ClassVar[Kind]

    def __init__(self, name: str, bus: Bus) -> None:
        self.name = name
        self.bus = bus
        self.params: dict[str, Any] = {}
        self.achievements: dict[str, Any] = {}
        self.log = logging.getLogger(f"dura.component.{name}")
        self.faults = FaultInjector(on_hang=self._hang)
        self._phase = ComponentPhase.CREATED
        self._hung = False
        self._changed = threading.Condition()
        self._jobs: queue.SimpleQueue[Callable[[], None]] = queue.SimpleQueue()
        self._pending = 0
        self._exit_code: int | None = None
        self._start_fault: Fault | None = None

    # --- hooks ------------------------------------------------------------------------

    def on_configure(self, params: dict[str, Any], achievements: dict[str, Any]) -> None:
        """Read parameters (:meth:`param`) and, for a warm start, achievements."""

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
    def phase(self) -> ComponentPhase:
        return self._phase

    @property
    def running(self) -> bool:
        return self._phase is ComponentPhase.RUNNING and not self._hung

    @property
    def ended(self) -> bool:
        return self._phase is ComponentPhase.STOPPED

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

    def publish(self, topic: str, payload: Mapping[str, Any]) -> None:
        """Publish on ``topic/<topic>``; ``stamp`` defaults to now."""
        if self.faults.silent:
            return
        stamp = payload["stamp"] if "stamp" in payload else time.time()
        self.bus.publish(keys.topic(topic), {**payload, "stamp": self.faults.stamp(stamp)})

    def subscribe(self, topic: str, handler: Callable[[Message], None]) -> None:
        """Call ``handler`` for each message on ``topic/<topic>`` while running."""

        def deliver(message: Message) -> None:
            if not self.running:
                return
            try:
                handler(message)
            except Exception:
                self._fail(f"the handler of topic '{topic}'")

        self.bus.subscribe(keys.topic(topic), deliver)

    def achieve(self, key: str, value: Any) -> None:
        """Store an achievement in the KB (through the executive): it comes back in
        ``on_configure`` when the component starts again (a warm start)."""
        self.achievements[key] = value
        try:
            self.bus.request(
                keys.api("component/achieve"),
                {"component": self.name, "key": key, "value": value},
                timeout=2.0,
            )
        except BusError as e:
            self.log.warning("achievement %r not stored: %s", key, e)

    def set_fact(self, fact: str) -> None:
        """Make a fact true in the robot's world (the planner's state), e.g.
        ``(battery_low)``, through the executive.

        Raises:
            BusError: the executive refused it (unknown predicate or object) or is gone.
        """
        self.bus.request(keys.api("state/set"), {"fact": fact}, timeout=5.0)

    def unset_fact(self, fact: str) -> None:
        """Make a fact false in the robot's world (see :meth:`set_fact`)."""
        self.bus.request(keys.api("state/unset"), {"fact": fact}, timeout=5.0)

    def at_rate(self, hz: float, step: Callable[[], None]) -> None:
        """Call ``step`` ``hz`` times a second while running (held while paused).

        Deadlines are absolute, so the rate does not drift; a loop that falls more
        than a period behind skips ahead instead of bursting.
        """
        if hz <= 0:
            raise ComponentError(f"a rate must be positive, not {hz}")
        period = 1.0 / hz

        def loop() -> None:
            due = time.monotonic()
            while self._wait_running():
                try:
                    step()
                except Exception:
                    self._fail(f"the rate loop {getattr(step, '__name__', step)!r}")
                    return
                due += period / self.faults.rate_factor()
                now = time.monotonic()
                if due < now - period:
                    due = now
                with self._changed:
                    self._changed.wait_for(lambda: self.ended, timeout=max(0.0, due - now))

        threading.Thread(target=loop, daemon=True, name=f"rate-{self.name}").start()

    def _wait_running(self) -> bool:
        """Block while not running; False once the component has ended."""
        with self._changed:
            self._changed.wait_for(lambda: self.running or self.ended)
            return not self.ended

    # --- lifecycle --------------------------------------------------------------------

    def _set_phase(self, phase: ComponentPhase) -> None:
        with self._changed:
            self._phase = phase
            self._changed.notify_all()

    def _expect(self, verb: str, *phases: ComponentPhase) -> None:
        if self._phase not in phases:
            raise ComponentError(f"cannot {verb} '{self.name}': it is {self._phase.value}")

    def configure(self, params: dict[str, Any], achievements: dict[str, Any]) -> None:
        self._expect("configure", ComponentPhase.CREATED, ComponentPhase.CONFIGURED)
        self.params = dict(params)
        self.achievements = dict(achievements)
        fault = self.params.get("fault")
        self._start_fault = Fault.parse(fault) if fault is not None else None
        self.on_configure(self.params, achievements)
        self._set_phase(ComponentPhase.CONFIGURED)

    def start(self) -> None:
        self._expect("start", ComponentPhase.CONFIGURED)
        self.on_start()
        self._set_phase(ComponentPhase.RUNNING)
        if self._start_fault is not None:
            self.faults.inject(self._start_fault)

    def pause(self) -> None:
        self._expect("pause", ComponentPhase.RUNNING)
        self._set_phase(ComponentPhase.PAUSED)
        self.on_pause()

    def resume(self) -> None:
        self._expect("resume", ComponentPhase.PAUSED)
        self.on_resume()
        self._set_phase(ComponentPhase.RUNNING)

    def reconfigure(self, params: dict[str, Any]) -> None:
        self._expect(
            "reconfigure", ComponentPhase.CONFIGURED, ComponentPhase.RUNNING, ComponentPhase.PAUSED
        )
        self.params.update(params)
        self.on_reconfigure(params)

    def stop(self) -> None:
        """Stop for good: loops end, the process exits with code 0."""
        if self.ended:
            return
        started = self._phase in (ComponentPhase.RUNNING, ComponentPhase.PAUSED)
        self._set_phase(ComponentPhase.STOPPED)
        if started:
            try:
                self.on_stop()
            except Exception:
                self.log.exception("on_stop failed")
        if self._exit_code is None:
            self._exit_code = 0

    def take_goal(self, goal_id: str, goal: dict[str, Any]) -> None:
        raise ComponentError(f"'{self.name}' is a {self.kind.value}: it takes no goals")

    def cancel_goal(self, goal_id: str) -> None:
        raise ComponentError(f"'{self.name}' is a {self.kind.value}: it has no goals")

    # --- commands ---------------------------------------------------------------------

    def _command(self, request: dict[str, Any]) -> dict[str, Any]:
        """Carry out one command (on the main thread)."""
        verb = request.get("cmd")
        try:
            command = Command(verb)
        except ValueError:
            verbs = ", ".join(c.value for c in Command)
            raise ComponentError(f"unknown command {verb!r} (choose from {verbs})") from None
        try:
            if command is Command.CONFIGURE:
                self.configure(_object(request, "params"), _object(request, "achievements"))
            elif command is Command.START:
                self.start()
            elif command is Command.PAUSE:
                self.pause()
            elif command is Command.RESUME:
                self.resume()
            elif command is Command.RECONFIGURE:
                self.reconfigure(_object(request, "params"))
            elif command is Command.STOP:
                self.stop()
            elif command is Command.GOAL:
                self.take_goal(str(request.get("goal_id", "")), _object(request, "goal"))
            elif command is Command.CANCEL:
                self.cancel_goal(str(request.get("goal_id", "")))
            else:
                self.faults.inject(Fault.parse(request.get("fault")))
        except DuraError:
            raise
        except Exception as e:
            self.log.exception("%s failed", command.value)
            raise ComponentError(f"{command.value} failed: {type(e).__name__}: {e}") from e
        return {"phase": self._phase.value}

    def _on_command(self, request: dict[str, Any]) -> dict[str, Any]:
        """Hand a command to the main thread and wait for its outcome (a bus thread)."""
        outcome: Future[dict[str, Any]] = Future()

        def job() -> None:
            try:
                outcome.set_result(self._command(request))
            except Exception as e:
                outcome.set_exception(e)

        with self._changed:
            self._pending += 1
        try:
            self._jobs.put(job)
            return outcome.result()
        finally:
            with self._changed:
                self._pending -= 1
                self._changed.notify_all()

    def _stop_soon(self) -> None:
        """Stop from any thread or a signal handler (SimpleQueue.put is reentrant)."""
        self._jobs.put(self.stop)

    def _fail(self, where: str) -> None:
        self.log.exception("unhandled exception in %s: '%s' ends", where, self.name)

        def end() -> None:
            self._set_phase(ComponentPhase.STOPPED)
            self._exit_code = 1

        self._jobs.put(end)

    def _hang(self) -> None:
        with self._changed:
            self._hung = True
            self._changed.notify_all()

        def block() -> None:
            for signum in (signal.SIGTERM, signal.SIGINT):
                signal.signal(signum, signal.SIG_IGN)
            threading.Event().wait()

        self._jobs.put(block)

    def _on_executive(self, key: str, alive: bool) -> None:
        if alive:
            return
        self.log.warning("the executive is gone: '%s' stops", self.name)
        deadline = threading.Timer(EXECUTIVE_GONE_DEADLINE, os._exit, (1,))
        deadline.daemon = True
        deadline.start()
        self._stop_soon()

    # --- process ----------------------------------------------------------------------

    def run(self, instance: str) -> int:
        """Take commands until stopped; returns the exit code. Call on the main thread."""
        for signum in (signal.SIGTERM, signal.SIGINT):
            signal.signal(signum, lambda *_: self._stop_soon())
        self.bus.serve(keys.component(self.name, "cmd"), self._on_command, threaded=True)
        self.bus.watch_alive(keys.EXECUTIVE_ALIVE, self._on_executive)
        self.bus.declare_alive(keys.component_alive(self.name, instance))
        while self._exit_code is None:
            self._jobs.get()()
        with self._changed:  # let the last command (stop) be answered
            self._changed.wait_for(lambda: self._pending == 0, timeout=1.0)
        return self._exit_code

    @classmethod
    def main(cls) -> None:
        """Run this component as its process's program; exits with its exit code."""
        sys.exit(cls.run_process())

    @classmethod
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
        try:
            with Bus(
                os.environ[keys.ENV_ROBOT],
                name=name,
                endpoint=os.environ[keys.ENV_ENDPOINT],
            ) as bus:
                instance = os.environ.get(keys.ENV_INSTANCE) or str(os.getpid())
                return cls(name, bus, *args).run(instance)
        except DuraError as e:
            logging.getLogger(f"dura.component.{name}").error("%s", e)
            return 1


class Functionality(Component, ABC):
    """A component that runs until it is stopped and provides capabilities."""

    kind = Kind.FUNCTIONALITY

    @abstractmethod
    def on_start(self) -> None:
        """Start publishing: rate loops (:meth:`at_rate`) and subscriptions."""


class Behavior(Component, ABC):
    """A component that carries out goals, one at a time, and returns their results.

    :meth:`execute` runs on a thread of its own; it should call :meth:`checkpoint`
    (or :meth:`sleep`) often: that is where it waits while paused and where a
    cancellation or a stop reaches it.
    """

    kind = Kind.BEHAVIOR

    def __init__(self, name: str, bus: Bus) -> None:
        super().__init__(name, bus)
        self._goal_id: str | None = None
        self._cancelled = False
        self._goal_thread: threading.Thread | None = None
        self.latest: dict[str, dict[str, Any]] = {}
        self._input_timeout: dict[str, float] = {}
        self._heard: dict[str, float] = {}
        self._fresh_since = time.monotonic()

    @abstractmethod
    def execute(self, goal: dict[str, Any]) -> dict[str, Any] | None:
        """Carry out one goal and return the result's value; raise :class:`GoalFailed` to fail."""

    # --- helpers ----------------------------------------------------------------------

    def watch(self, *topics: str, timeout: float) -> None:
        """Watch inputs a goal needs (call in :meth:`on_start`): :meth:`check_inputs`
        fails the goal when one of them has been silent for ``timeout`` seconds, counted
        from its last message, the goal's start and the last resume. The newest message
        of each is in :attr:`latest`."""

        def hearing(topic: str) -> Callable[[Message], None]:
            def heard(message: Message) -> None:
                self._heard[topic] = time.monotonic()
                self.latest[topic] = message.payload

            return heard

        for topic in topics:
            self._input_timeout[topic] = timeout
            self.subscribe(topic, hearing(topic))

    def check_inputs(self) -> None:
        """Raise :class:`GoalFailed` if a watched input has gone silent."""
        now = time.monotonic()
        for topic, timeout in self._input_timeout.items():
            silent = now - max(self._heard.get(topic, 0.0), self._fresh_since)
            if silent > timeout:
                raise GoalFailed(f"no {topic} for {silent:.1f} s")

    def wait_until(self, condition: Callable[[], bool], timeout: float, what: str) -> None:
        """Wait (running time) until ``condition()`` holds, checking the watched inputs.

        Raises:
            GoalFailed: not within ``timeout`` seconds ("no <what> within ... s").
        """
        waited = 0.0
        while not condition():
            if waited > timeout:
                raise GoalFailed(f"no {what} within {timeout:g} s")
            self.sleep(WAIT_STEP)
            self.check_inputs()
            waited += WAIT_STEP

    def work_for(
        self,
        seconds: float,
        step: Callable[[float], None],
        *,
        job: str,
        rate: float = 10.0,
        store_every: float = 1.0,
    ) -> None:
        """Work for ``seconds`` of running time: call ``step(fraction_done)`` ``rate``
        times a second, check the watched inputs before each step, publish the progress
        as feedback and store it as the achievement ``progress`` every ``store_every``
        seconds. A behavior restarted on the same ``job`` (e.g. the same target) goes on
        from the stored progress: a warm start.
        """
        stored = self.achievements.get("progress")
        done = 0.0
        if isinstance(stored, dict) and stored.get("job") == job:
            done = float(stored.get("done", 0.0))
            self.log.info("warm start of %s at %.0f%%", job, done * 100)
        period = 1.0 / rate
        since_stored = 0.0
        while done < 1.0:
            self.sleep(period)
            self.check_inputs()
            done = min(1.0, done + period / seconds)
            step(done)
            self.feedback(job=job, done=round(done, 3))
            since_stored += period
            if since_stored >= store_every and done < 1.0:
                self.achieve("progress", {"job": job, "done": done})
                since_stored = 0.0
        self.achievements.pop("progress", None)  # the executive forgets it on success

    def feedback(self, **values: Any) -> None:
        """Publish feedback on the running goal (``component/<name>/feedback``)."""
        goal_id = self._goal_id
        if goal_id is None or self.faults.silent:
            return
        self.bus.publish(
            keys.component(self.name, "feedback"),
            {"component": self.name, "goal_id": goal_id, "feedback": values},
        )

    def checkpoint(self) -> None:
        """Wait while paused; raise :class:`GoalCancelled` once cancelled or stopped."""
        with self._changed:
            self._changed.wait_for(lambda: self.running or self.ended or self._cancelled)
            if self.ended or self._cancelled:
                raise GoalCancelled("stopped" if self.ended else "cancelled")

    def sleep(self, seconds: float) -> None:
        """Sleep ``seconds`` of running time (time paused does not count)."""
        remaining = seconds
        while True:
            self.checkpoint()
            if remaining <= 0:
                return
            began = time.monotonic()
            with self._changed:
                self._changed.wait_for(
                    lambda: not self.running or self._cancelled, timeout=remaining
                )
            remaining -= time.monotonic() - began

    # --- lifecycle --------------------------------------------------------------------

    def stop(self) -> None:
        super().stop()
        thread = self._goal_thread
        if thread is not None:
            thread.join(GOAL_STOP_TIMEOUT)

    def take_goal(self, goal_id: str, goal: dict[str, Any]) -> None:
        if not goal_id:
            raise ComponentError("a goal needs a 'goal_id'")
        if not self.running:
            raise ComponentError(f"'{self.name}' is {self._phase.value}: it takes no goal now")
        if self._goal_id is not None:
            raise ComponentError(f"'{self.name}' is busy with goal {self._goal_id}")
        with self._changed:
            self._goal_id, self._cancelled = goal_id, False
        self._goal_thread = threading.Thread(
            target=self._run_goal, args=(goal_id, goal), daemon=True, name=f"goal-{goal_id}"
        )
        self._goal_thread.start()

    def cancel_goal(self, goal_id: str) -> None:
        if goal_id != self._goal_id:
            raise ComponentError(f"'{self.name}' has no running goal {goal_id!r}")
        with self._changed:
            self._cancelled = True
            self._changed.notify_all()

    def resume(self) -> None:
        self._fresh_since = time.monotonic()  # inputs get their timeout again
        super().resume()

    def _run_goal(self, goal_id: str, goal: dict[str, Any]) -> None:
        status, value, reason = GoalStatus.FAILED, {}, ""
        self._fresh_since = time.monotonic()
        try:
            returned = self.execute(goal)
            if returned is not None and not isinstance(returned, dict):
                raise GoalFailed(f"execute returned a {type(returned).__name__}, not a dict")
            json.dumps(returned)
            status, value = GoalStatus.SUCCEEDED, returned or {}
        except GoalCancelled as e:
            status, reason = GoalStatus.CANCELLED, str(e)
        except GoalFailed as e:
            reason = str(e)
            self.log.warning("goal %s failed: %s", goal_id, reason)
        except Exception as e:
            reason = f"{type(e).__name__}: {e}"
            self.log.exception("goal %s failed", goal_id)
        with self._changed:
            self._goal_id = None
        result = GoalResult(self.name, goal_id, status, value, reason, time.time())
        self.bus.publish(keys.component(self.name, "result"), result.to_payload())
