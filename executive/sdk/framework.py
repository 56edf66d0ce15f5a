"""The framework side of a component process: its phase, lifecycle commands, main loop.

A component author never calls or overrides anything here: :class:`Framework` drives
one :class:`~executive.sdk.component.Component` and calls its ``on_*`` hooks. It takes
the lifecycle commands of ``component/<name>/cmd`` (declared in
:mod:`executive.bus.api.components`, checked there) on a bus thread and carries each out
on the process's main thread, so that every hook runs there. It refuses a command that
does not fit the current phase, with the reason. The process ends with exit code 0 once
stopped (a command, SIGTERM or SIGINT, or the executive's liveliness token vanishing)
and with 1 when an exception escapes a rate loop or a subscription handler.
"""

from __future__ import annotations

import os
import queue
import signal
import threading
from collections.abc import Callable
from concurrent.futures import Future
from typing import TYPE_CHECKING, Any

from executive.bus import keys
from executive.bus.api.component_commands import (
    CancelGoal,
    CommandReply,
    ComponentCommand,
    Configure,
    InjectFault,
    Pause,
    Reconfigure,
    Resume,
    Start,
    Stop,
    TakeGoal,
)
from executive.bus.states import ComponentPhase
from executive.sdk.fault_injection import Fault
from knowledge.errors import ComponentError, DuraError

if TYPE_CHECKING:
    from executive.sdk.component import Component
    from executive.sdk.goal import GoalRunner

# After the executive vanished, a component that has not ended by then is ended hard.
EXECUTIVE_GONE_DEADLINE = 1.5
# How long a stop waits for a running goal to publish its (cancelled) result.
GOAL_STOP_TIMEOUT = 2.0
# CPython runs signal handlers on the main thread, but the kernel may hand SIGTERM to
# another thread (Zenoh's), which does not wake a main thread blocked on the job queue:
# it wakes this often to let a pending handler run.
SIGNAL_POLL = 0.1


class Framework:
    """Drives one component through its lifecycle and runs its process's main loop.

    ``changed`` is notified at every change of the phase (and of a goal's
    cancellation): rate loops, subscription handlers and goals wait on it.
    """

    def __init__(self, component: Component) -> None:
        self.component = component
        self.phase = ComponentPhase.CREATED
        self.hung = False
        self.changed = threading.Condition()
        self.goals: GoalRunner | None = None  # a behavior's
        self.exit_code: int | None = None
        self._jobs: queue.SimpleQueue[Callable[[], None]] = queue.SimpleQueue()
        self._pending = 0
        self._start_fault: Fault | None = None

    @property
    def running(self) -> bool:
        return self.phase is ComponentPhase.RUNNING and not self.hung

    @property
    def ended(self) -> bool:
        return self.phase is ComponentPhase.STOPPED

    def wait(self, predicate: Callable[[], bool], timeout: float | None = None) -> bool:
        """Wait until ``predicate()`` holds (looked at on every change); whether it does."""
        with self.changed:
            return self.changed.wait_for(predicate, timeout)

    def wait_running(self) -> bool:
        """Block while not running; False once the component has ended."""
        self.wait(lambda: self.running or self.ended)
        return not self.ended

    # --- the lifecycle ----------------------------------------------------------------

    def _set_phase(self, phase: ComponentPhase) -> None:
        with self.changed:
            self.phase = phase
            self.changed.notify_all()

    def _expect(self, verb: str, *phases: ComponentPhase) -> None:
        if self.phase not in phases:
            raise ComponentError(f"cannot {verb} '{self.component.name}': it is {self.phase.value}")

    def configure(self, params: dict[str, Any], achievements: dict[str, Any]) -> None:
        self._expect("configure", ComponentPhase.CREATED, ComponentPhase.CONFIGURED)
        component = self.component
        component.params = dict(params)
        component.achievements = dict(achievements)
        fault = component.params.get("fault")
        self._start_fault = Fault.parse(fault) if fault is not None else None
        component.on_configure(component.params, achievements)
        self._set_phase(ComponentPhase.CONFIGURED)

    def start(self) -> None:
        self._expect("start", ComponentPhase.CONFIGURED)
        self.component.on_start()
        self._set_phase(ComponentPhase.RUNNING)
        if self._start_fault is not None:
            self.component.faults.inject(self._start_fault)

    def pause(self) -> None:
        self._expect("pause", ComponentPhase.RUNNING)
        self._set_phase(ComponentPhase.PAUSED)
        self.component.on_pause()

    def resume(self) -> None:
        self._expect("resume", ComponentPhase.PAUSED)
        if self.goals is not None:
            self.goals.resumed()
        self.component.on_resume()
        self._set_phase(ComponentPhase.RUNNING)

    def reconfigure(self, params: dict[str, Any]) -> None:
        """Hand changed parameters to the component's ``on_reconfigure``; refused by a
        component without one (the executive then restarts it with them)."""
        self._expect(
            "reconfigure", ComponentPhase.CONFIGURED, ComponentPhase.RUNNING, ComponentPhase.PAUSED
        )
        from executive.sdk.component import Component  # here: it imports this module

        component = self.component
        if type(component).on_reconfigure is Component.on_reconfigure:
            raise ComponentError(
                f"'{component.name}' cannot change its parameters while it runs "
                "(it has no on_reconfigure)"
            )
        component.params.update(params)
        component.on_reconfigure(params)

    def stop(self) -> None:
        """Stop for good: loops end, a running goal is cancelled, the process exits (0)."""
        if not self.ended:
            started = self.phase in (ComponentPhase.RUNNING, ComponentPhase.PAUSED)
            self._set_phase(ComponentPhase.STOPPED)
            if started:
                try:
                    self.component.on_stop()
                except Exception:
                    self.component.log.exception("on_stop failed")
            if self.exit_code is None:
                self.exit_code = 0
        if self.goals is not None:
            self.goals.join(GOAL_STOP_TIMEOUT)

    def end(self, exit_code: int) -> None:
        """Stop, and end the process with ``exit_code`` (on the main thread)."""
        self.stop()
        self.exit_code = exit_code

    def _goal_runner(self, refusal: str) -> GoalRunner:
        if self.goals is None:
            component = self.component
            raise ComponentError(f"'{component.name}' is a {component.kind.value}: {refusal}")
        return self.goals

    # --- commands ---------------------------------------------------------------------

    def carry_out(self, request: dict[str, Any]) -> dict[str, Any]:
        """Carry out one command (on the main thread); the reply.

        Raises:
            DuraError: the command is malformed or refused (the reason).
        """
        command = ComponentCommand.from_request(request)
        verb = command.verb.value
        try:
            match command:
                case Configure(params=params, achievements=achievements):
                    self.configure(params, achievements)
                case Start():
                    self.start()
                case Pause():
                    self.pause()
                case Resume():
                    self.resume()
                case Reconfigure(params=params):
                    self.reconfigure(params)
                case Stop():
                    self.stop()
                case TakeGoal(goal_id=goal_id, goal=goal):
                    self._goal_runner("it takes no goals").take(goal_id, goal)
                case CancelGoal(goal_id=goal_id):
                    self._goal_runner("it has no goals").cancel(goal_id)
                case InjectFault(fault=fault):
                    self.component.faults.inject(Fault.parse(fault))
                case _:
                    raise TypeError(f"no handler for the command {verb!r}")
        except DuraError:
            raise
        except Exception as e:
            self.component.log.exception("%s failed", verb)
            raise ComponentError(f"{verb} failed: {type(e).__name__}: {e}") from e
        return CommandReply(self.phase).to_payload()

    def _on_command(self, request: dict[str, Any]) -> dict[str, Any]:
        """Hand a command to the main thread and wait for its outcome (a bus thread)."""
        outcome: Future[dict[str, Any]] = Future()

        def job() -> None:
            try:
                outcome.set_result(self.carry_out(request))
            except Exception as e:
                outcome.set_exception(e)

        with self.changed:
            self._pending += 1
        try:
            self._jobs.put(job)
            return outcome.result()
        finally:
            with self.changed:
                self._pending -= 1
                self.changed.notify_all()

    def post(self, job: Callable[[], None]) -> None:
        """Run ``job`` on the main thread (from any thread, even a signal handler:
        SimpleQueue.put is reentrant)."""
        self._jobs.put(job)

    def fail(self, where: str) -> None:
        """End the process with exit code 1 (an exception escaped ``where``)."""
        self.component.log.exception(
            "unhandled exception in %s: '%s' ends", where, self.component.name
        )

        def end() -> None:
            self._set_phase(ComponentPhase.STOPPED)
            self.exit_code = 1

        self.post(end)

    def hang(self) -> None:
        """Stop responding (an injected fault): no commands, no output, no SIGTERM."""
        with self.changed:
            self.hung = True
            self.changed.notify_all()

        def block() -> None:
            for signum in (signal.SIGTERM, signal.SIGINT):
                signal.signal(signum, signal.SIG_IGN)
            threading.Event().wait()

        self.post(block)

    def _on_executive(self, key: str, alive: bool) -> None:
        if alive:
            return
        self.component.log.warning("the executive is gone: '%s' stops", self.component.name)
        deadline = threading.Timer(EXECUTIVE_GONE_DEADLINE, os._exit, (1,))
        deadline.daemon = True
        deadline.start()
        self.post(self.stop)

    # --- the process ------------------------------------------------------------------

    def run(self, instance: str) -> int:
        """Take commands until stopped; returns the exit code. Call on the main thread."""
        for signum in (signal.SIGTERM, signal.SIGINT):
            signal.signal(signum, lambda *_: self.post(self.stop))
        bus, name = self.component.bus, self.component.name
        bus.serve(keys.component(name, "cmd"), self._on_command, threaded=True)
        bus.watch_alive(keys.EXECUTIVE_ALIVE, self._on_executive)
        bus.declare_alive(keys.component_alive(name, instance))
        while self.exit_code is None:
            try:
                job = self._jobs.get(timeout=SIGNAL_POLL)
            except queue.Empty:
                continue  # back in Python, so that a pending signal handler runs
            job()
        with self.changed:  # let the last command (stop) be answered
            self.changed.wait_for(lambda: self._pending == 0, timeout=1.0)
        return self.exit_code
