"""Component lifecycles: start, stop, pause, resume, reconfigure and other commands.

A start waits until the component is ready: its process declared its liveliness
token, was configured (parameters from the robot description and the KB, achievements
from the KB) and started, all within the component's start-up timeout; else it is
killed and FAILED. A stop asks the component to stop, then sends SIGTERM to its
process group after a grace period, then SIGKILL. When a process ends, this module
decides what its end means (STOPPED, EXITED or FAILED) and tells the owner of its goals.

Each component's state changes under one lock, so that states are recorded
(:mod:`executive.runtime.states`) in the order they happen; one lifecycle operation
runs at a time per component.
"""

from __future__ import annotations

import contextlib
import logging
import signal
import threading
import time
import uuid
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from executive.bus import keys, security
from executive.bus.api.component_commands import (
    COMMANDS,
    ComponentCommand,
    Configure,
    Start,
    Stop,
)
from executive.bus.payloads import ComponentState
from executive.bus.security import Credentials
from executive.bus.session import Bus
from executive.bus.states import Command, Lifecycle
from executive.runtime.process_host import Launch, LocalHost, ProcessHandle, ProcessHost
from executive.runtime.processes import ProcessThread
from executive.runtime.remote_host import Hosts
from executive.runtime.spawn import command, describe_exit
from executive.runtime.states import StateRecords
from knowledge.description import ComponentSpec, RobotDescription
from knowledge.errors import BusError, ComponentError
from knowledge.knowledge_base import KnowledgeBase

log = logging.getLogger("dura.launcher")

ProcessEnded = Callable[[str, bool, str], None]
"""Told ``(component, stopping, how)`` when a component's process has ended."""


def local_endpoint(endpoint: str) -> str:
    """Where a child on this machine reaches an executive listening on ``endpoint``."""
    return endpoint.replace("/0.0.0.0:", "/127.0.0.1:").replace("/[::]:", "/[::1]:")


@dataclass(eq=False)
class _Run:
    """One started process, as its lifecycle sees it."""

    process: ProcessHandle
    host: ProcessHost
    instance: str  # names its liveliness token
    woken: threading.Event = field(default_factory=threading.Event)  # token seen, or exited
    exited: threading.Event = field(default_factory=threading.Event)
    announced: bool = False  # its liveliness token was seen
    ready: bool = False
    stopping: bool = False
    failure: str = ""


@dataclass(eq=False)
class _Slot:
    """One component of the robot and where it is in its lifecycle."""

    spec: ComponentSpec
    state: ComponentState
    run: _Run | None = None
    lock: threading.Lock = field(default_factory=threading.Lock)  # one operation at a time


class LifecycleControl:
    """Drives the robot's components through their lifecycles and records their states.

    Args:
        robot: the robot; commands run in its description's folder.
        bus: the executive's bus session (components connect to its endpoint).
        kb: parameters and achievements come from here; states go here.
        log_dir, log_max_bytes, log_backups: the components' log files.
        grace: seconds a component gets to answer a command, and to exit after a stop
            command and again after SIGTERM.
        on_process_end: told when a component's process has ended (on the launcher
            thread, after its state is recorded).
    """

    def __init__(
        self,
        robot: RobotDescription,
        bus: Bus,
        kb: KnowledgeBase,
        *,
        log_dir: Path,
        grace: float,
        log_max_bytes: int,
        log_backups: int,
        on_process_end: ProcessEnded,
        credentials: Credentials | None = None,
        run_id: str | None = None,
    ) -> None:
        self.robot = robot
        self.run_id = run_id
        self.bus = bus
        self.kb = kb
        self.grace = grace
        self.credentials = credentials
        self._on_process_end = on_process_end
        self._slots = {
            name: _Slot(spec, ComponentState(name, Lifecycle.STOPPED, reason="not started"))
            for name, spec in robot.components.items()
        }
        self._lock = threading.Lock()
        self._tokens: set[str] = set()  # instances whose liveliness token is there
        self._closing = False
        self._watch: Any = None
        self.records = StateRecords(bus, kb)
        processes = ProcessThread(
            log_dir,
            log_max_bytes=log_max_bytes,
            log_backups=log_backups,
            on_exit=lambda process, code, signum: self._exited(process, code, signum, ""),
            grace=grace,
        )
        local = LocalHost(robot, local_endpoint(bus.endpoint), processes)
        self.hosts = Hosts(robot, bus, kb, local, self._exited)

    def open(self) -> None:
        self.hosts.open()
        self.records.open()
        self._watch = self.bus.watch_alive(keys.component_alive("*", "*"), self._on_token)

    def stop_all(self) -> None:
        """Stop every component, all at once; refuse starts from now on."""
        self._closing = True
        stoppers = [
            threading.Thread(target=self.stop, args=(name,), name=f"stop-{name}")
            for name, slot in self._slots.items()
            if slot.run is not None
        ]
        for thread in stoppers:
            thread.start()
        for thread in stoppers:
            thread.join()

    def close(self) -> None:
        """End the threads (after :meth:`stop_all`)."""
        with contextlib.suppress(Exception):
            self._watch.undeclare()
        self.hosts.close()
        self.records.close()

    # --- queries ----------------------------------------------------------------------

    def spec(self, name: str) -> ComponentSpec:
        """The component's description.

        Raises:
            ComponentError: the robot has no such component.
        """
        return self._slot(name).spec

    def _slot(self, name: str) -> _Slot:
        slot = self._slots.get(name)
        if slot is None:
            known = ", ".join(self._slots) or "none"
            raise ComponentError(f"no component '{name}' in robot '{self.robot.name}' ({known})")
        return slot

    def state(self, name: str) -> ComponentState:
        return self._slot(name).state

    def states(self) -> list[ComponentState]:
        """The state of every component, in the robot description's order."""
        return [slot.state for slot in self._slots.values()]

    # --- starting ---------------------------------------------------------------------

    def start(self, name: str) -> ComponentState:
        """Start a component and wait until it is ready, or failed (a result)."""
        slot = self._slot(name)
        with slot.lock:
            if slot.state.state.is_alive:
                return slot.state
            if self._closing:
                raise ComponentError(f"cannot start '{name}': the launcher is closing")
            deadline = time.monotonic() + slot.spec.startup_timeout
            try:
                run = self._spawn(slot)
            except (OSError, ComponentError) as e:
                program = command(slot.spec.command)[0] if slot.spec.command else slot.spec.name
                reason = (
                    f"cannot run {program!r}: {e.strerror or e}"
                    if isinstance(e, OSError)
                    else f"cannot start: {e}"
                )
                with self._lock:
                    return self._set(slot, Lifecycle.FAILED, reason=reason)
            failure = self._bring_up(slot, run, deadline)
            pid = run.process.program()  # found now, not under the lock
            with self._lock:
                ready = not run.exited.is_set() and not failure
                if ready:
                    run.ready = True
                    state = self._set(slot, Lifecycle.READY, pid=pid)
            if ready:
                run.host.note(run.process, f"{name} ready (pid {pid})")
                return state
            if failure:
                run.failure = failure
                self._terminate(run)
            run.exited.wait()
            return slot.state

    def _spawn(self, slot: _Slot) -> _Run:
        """Start the process on its host and record it STARTING (before its end can be
        handled)."""
        spec = slot.spec
        instance = uuid.uuid4().hex[:12]
        login = None
        if self.credentials is not None:  # its own user: it may do only a component's part
            login = self.credentials.login(security.component_user(spec.name))
        host = self.hosts.of(spec)
        runs: list[_Run] = []

        def started(process: ProcessHandle) -> None:
            run = _Run(process, host, instance)
            runs.append(run)
            with self._lock:
                slot.run = run
                self._set(slot, Lifecycle.STARTING, pid=process.pid)
                self._announce(run)  # in case its token came first

        host.spawn(Launch(spec, instance, login, self.run_id), started)
        return runs[0]

    def _bring_up(self, slot: _Slot, run: _Run, deadline: float) -> str:
        """Wait for the process's token, configure and start it; the failure, if any."""
        timeout = slot.spec.startup_timeout
        if not run.woken.wait(max(0.0, deadline - time.monotonic())):
            return f"not ready within {timeout:g} s (no answer)"
        if run.exited.is_set():
            return ""
        name = slot.spec.name
        params = {**slot.spec.params, **self.kb.parameters(name)}
        configure = Configure(params=params, achievements=self.kb.achievements(name))
        for request in (configure, Start()):
            verb = request.verb.value
            remaining = deadline - time.monotonic()
            if remaining <= 0:
                return f"not ready within {timeout:g} s (no answer to {verb})"
            try:
                self._request(name, request, remaining)
            except BusError as e:
                if run.exited.is_set():
                    return ""
                return f"{verb} failed: {e}"
        return ""

    def _on_token(self, key: str, alive: bool) -> None:
        """A component process declared (or dropped) its liveliness token."""
        parts = key.split("/")
        if len(parts) != 4:
            return
        with self._lock:
            if not alive:
                self._tokens.discard(parts[3])
                return
            self._tokens.add(parts[3])
            slot = self._slots.get(parts[2])
            if slot is not None and slot.run is not None:
                self._announce(slot.run)

    def _announce(self, run: _Run) -> None:
        """Wake the start of a process whose token is there (with ``self._lock`` held)."""
        if run.instance in self._tokens:
            run.announced = True
            run.woken.set()

    # --- stopping ---------------------------------------------------------------------

    def stop(
        self, name: str, reason: str = "stopped", *, begun: threading.Event | None = None
    ) -> ComponentState:
        """Stop a component and wait until its process is gone; returns its final state.

        ``begun`` is set once the stop holds the component (a start waits for it)."""
        slot = self._slot(name)
        with slot.lock:
            try:
                with self._lock:
                    run = slot.run
                    if run is None or run.exited.is_set():
                        return slot.state
                    run.stopping = True
                    self._set(slot, Lifecycle.STOPPING, pid=run.process.program(), reason=reason)
            finally:
                if begun is not None:
                    begun.set()
            if run.announced:
                with contextlib.suppress(BusError):
                    self._request(name, Stop(), self.grace)
            if not run.exited.wait(self.grace):
                self._terminate(run)
            run.exited.wait()
            return slot.state

    def stop_soon(self, name: str, reason: str = "stopped") -> None:
        """Begin to stop a component and return: the stop goes on on a thread of its own,
        and a start of the component waits for it."""
        self._slot(name)  # refuses an unknown name here
        begun = threading.Event()
        threading.Thread(
            target=self.stop, args=(name, reason), kwargs={"begun": begun},
            name=f"stop-{name}", daemon=True,
        ).start()  # fmt: skip
        begun.wait()

    def _terminate(self, run: _Run) -> None:
        """SIGTERM to the process group; after the grace period its supervisor kills
        the whole tree, and after another the group is killed (returns at once once it
        is gone)."""
        host, process = run.host, run.process
        host.signal(process, signal.SIGTERM)
        if run.exited.wait(self.grace):
            return
        log.warning("'%s' ignored SIGTERM: SIGKILL to its process tree", process.name)
        host.signal(process, signal.SIGUSR1, group=False)
        if not run.exited.wait(self.grace):
            host.signal(process, signal.SIGKILL)

    def _exited(
        self, process: ProcessHandle, exit_code: int | None, signum: int | None, how: str
    ) -> None:
        """A process ended: record what its end means (on the thread that learnt of it:
        the launcher thread, or the bus's for a remote one). ``how``: why, when no exit
        code or signal says it (its host was lost)."""
        slot = self._slots[process.name]
        run = slot.run
        if run is None or run.process is not process:
            raise ComponentError(f"'{process.name}' (pid {process.pid}) was not started here")
        lost = bool(how)  # its host was lost: its log went with it
        how = how or describe_exit(exit_code, signum)
        output = process.output
        failed = not run.stopping and not lost and (exit_code != 0 or signum is not None)
        # a signal's victim did not say why: its last words are not its reason
        said = output if signum is None else ()
        told = explained(how, process.name, said) if failed else how
        with self._lock:
            if run.failure:
                state, reason = Lifecycle.FAILED, run.failure
            elif run.stopping:
                state, reason = Lifecycle.STOPPED, slot.state.reason or "stopped"
            elif not run.ready:
                early = f"{how} before it was ready"
                state, reason = (
                    Lifecycle.FAILED,
                    (explained(early, process.name, said) if failed else early),
                )
            else:
                state, reason = Lifecycle.EXITED, told
            process.finish(f"{state.value}: {how}")
            self._set(
                slot,
                state,
                pid=process.program(),
                exit_code=exit_code,
                signum=signum,
                reason=reason,
                output=output if failed else None,
            )
            slot.run = None
            run.exited.set()
            run.woken.set()
        self._on_process_end(process.name, run.stopping, told)

    # --- commands ---------------------------------------------------------------------

    def _request(self, name: str, request: ComponentCommand, timeout: float) -> dict[str, Any]:
        return self.bus.request(keys.component(name, "cmd"), request.to_request(), timeout=timeout)

    def command(self, name: str, verb: Command, **fields: Any) -> dict[str, Any]:
        """Send a lifecycle command to a running component and return its reply.

        Raises:
            ComponentError: the component is not running, refused or did not answer.
        """
        slot = self._slot(name)
        run = slot.run
        if run is None or not run.ready:
            raise ComponentError(f"'{name}' is {slot.state.state.value}, not running")
        request = next(c for c in COMMANDS if c.verb is verb)(**fields)
        try:
            return self._request(name, request, self.grace)
        except BusError as e:
            raise ComponentError(f"'{name}' refused {verb.value}: {e}") from e

    def pause(self, name: str) -> ComponentState:
        return self._switch(name, Command.PAUSE, Lifecycle.READY, Lifecycle.PAUSED)

    def resume(self, name: str) -> ComponentState:
        return self._switch(name, Command.RESUME, Lifecycle.PAUSED, Lifecycle.READY)

    def _switch(
        self, name: str, verb: Command, before: Lifecycle, after: Lifecycle
    ) -> ComponentState:
        slot = self._slot(name)
        with slot.lock:
            if slot.state.state is after:
                return slot.state
            if slot.state.state is not before:
                raise ComponentError(
                    f"cannot {verb.value} '{name}': it is {slot.state.state.value}"
                )
            self.command(name, verb)
            with self._lock:
                run = slot.run
                if run is None or run.exited.is_set():
                    return slot.state
                return self._set(slot, after, pid=run.process.program())

    def reconfigure(self, name: str, params: Mapping[str, Any]) -> None:
        """Hand changed parameters to a running component."""
        self.command(name, Command.RECONFIGURE, params=dict(params))

    def inject_fault(self, name: str, fault: str | Mapping[str, Any]) -> None:
        """Make a running component misbehave (see :mod:`executive.sdk.fault_injection`)."""
        self.command(name, Command.INJECT_FAULT, fault=fault)

    # --- state ------------------------------------------------------------------------

    def _set(
        self,
        slot: _Slot,
        state: Lifecycle,
        *,
        pid: int | None = None,
        exit_code: int | None = None,
        signum: int | None = None,
        reason: str = "",
        output: tuple[str, ...] | None = None,
    ) -> ComponentState:
        """Record a new state (with ``self._lock`` held: keeps the order). What its
        process wrote last when it last failed stays with it (``output``) until it fails
        again: a restarted component still tells why it had to be."""
        if output is None:
            output = slot.state.output
        new = ComponentState(
            slot.spec.name, state, pid, exit_code, signum, reason, time.time(), output
        )
        slot.state = new
        self.records.record(new)
        return new


def explained(how: str, name: str, output: tuple[str, ...]) -> str:
    """How a component's process ended, with the last line it wrote (its exception) and
    where to read the rest: ``exited with code 1: TypeError: ... (dura component logs
    barista)``."""
    said = f": {output[-1].strip()}" if output else ""
    return f"{how}{said} (dura component logs {name})"
