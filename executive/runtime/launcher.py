"""The launcher: starts, watches and stops component processes (thesis 5.1.4, 6.1).

Each component runs in a process group of its own, with its stdout and stderr piped
into a log file rotated by size. One long-lived thread forks every child (children die
with it: see :mod:`executive.runtime.spawn`) and waits on a pidfd per child, so an exit is
known at once: the thread kills whatever is left of the child's process group, reaps
the child and reports the new state on ``component/<name>/state``. A second thread
writes every state to the KB event log and calls the listeners, in order.

A start waits until the component is ready: its process declared its liveliness
token, was configured (parameters from the robot description and the KB, achievements
from the KB) and started. A stop asks the component to stop, then sends SIGTERM to its
process group after a grace period, then SIGKILL.
"""

from __future__ import annotations

import contextlib
import logging
import os
import queue
import selectors
import signal
import subprocess
import threading
import time
import uuid
from collections.abc import Callable, Mapping
from concurrent.futures import Future
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, TypeVar

from executive.bus import keys
from executive.bus.payloads import (
    Command,
    ComponentState,
    GoalResult,
    GoalStatus,
    Lifecycle,
)
from executive.bus.session import Bus, Message
from executive.runtime.logfile import LogFile, tail
from executive.runtime.spawn import command, describe_exit, exit_status, signal_group, spawn
from knowledge.description import ComponentSpec, Kind, RobotDescription
from knowledge.errors import BusError, ComponentError, DuraError
from knowledge.knowledge_base import KnowledgeBase

log = logging.getLogger("dura.launcher")

T = TypeVar("T")
Listener = Callable[[ComponentState], None]


def local_endpoint(endpoint: str) -> str:
    """Where a child on this machine reaches an executive listening on ``endpoint``."""
    return endpoint.replace("/0.0.0.0:", "/127.0.0.1:").replace("/[::]:", "/[::1]:")


class GoalHandle:
    """A goal sent to a behavior: its feedback as it comes, and its result."""

    def __init__(
        self,
        launcher: Launcher,
        component: str,
        goal_id: str,
        goal: Mapping[str, Any],
        task_id: int | None,
    ) -> None:
        self.component = component
        self.goal_id = goal_id
        self.goal = dict(goal)
        self.task_id = task_id
        self.feedback: dict[str, Any] = {}
        self._launcher = launcher
        self._result: GoalResult | None = None
        self._done = threading.Event()
        self._lock = threading.Lock()
        self._feedback_listeners: list[Callable[[dict[str, Any]], None]] = []
        self._done_callbacks: list[Callable[[GoalResult], None]] = []

    @property
    def result(self) -> GoalResult | None:
        """The result, once the goal has ended."""
        return self._result

    def done(self) -> bool:
        return self._done.is_set()

    def wait(self, timeout: float | None = None) -> GoalResult | None:
        """Wait for the result; None if the goal has not ended within ``timeout``."""
        self._done.wait(timeout)
        return self._result

    def cancel(self) -> None:
        """Ask the behavior to cancel the goal (the result says CANCELLED)."""
        self._launcher.command(self.component, Command.CANCEL, goal_id=self.goal_id)

    def add_feedback_listener(self, listener: Callable[[dict[str, Any]], None]) -> None:
        with self._lock:
            self._feedback_listeners.append(listener)

    def add_done_callback(self, callback: Callable[[GoalResult], None]) -> None:
        """Call ``callback(result)`` when the goal ends (at once if it has)."""
        with self._lock:
            if self._result is None:
                self._done_callbacks.append(callback)
                return
            result = self._result
        callback(result)

    def _feedback(self, feedback: dict[str, Any]) -> None:
        self.feedback = feedback
        with self._lock:
            listeners = list(self._feedback_listeners)
        for listener in listeners:
            _call_safely(listener, feedback)

    def _resolve(self, result: GoalResult) -> bool:
        with self._lock:
            if self._result is not None:
                return False
            self._result = result
            callbacks, self._done_callbacks = self._done_callbacks, []
        self._done.set()
        for callback in callbacks:
            _call_safely(callback, result)
        return True


def _call_safely(fn: Callable[[Any], None], arg: Any) -> None:
    try:
        fn(arg)
    except Exception:
        log.exception("callback %r failed", fn)


@dataclass(eq=False)
class _Process:
    """One started component process."""

    name: str
    instance: str
    pid: int
    popen: subprocess.Popen[bytes]
    pidfd: int
    pipe: int
    log: LogFile
    woken: threading.Event = field(default_factory=threading.Event)  # token seen, or exited
    exited: threading.Event = field(default_factory=threading.Event)
    announced: bool = False  # its liveliness token was seen
    ready: bool = False
    stopping: bool = False
    failure: str = ""


@dataclass(eq=False)
class _Slot:
    """One component of the robot and what the launcher knows of it."""

    spec: ComponentSpec
    state: ComponentState
    process: _Process | None = None
    lock: threading.Lock = field(default_factory=threading.Lock)  # one lifecycle op at a time
    goals: dict[str, GoalHandle] = field(default_factory=dict)


class Launcher:
    """Starts, stops and watches the robot's component processes.

    Args:
        robot: the robot; commands run in its description's folder.
        bus: the executive's bus session (components connect to its endpoint).
        kb: parameters and achievements come from here; states, return values and
            achievements go here.
        log_dir: where ``<name>.log`` files go.
        grace: seconds a component gets to answer a command, and to exit after a stop
            command and again after SIGTERM.
        log_max_bytes, log_backups: log rotation.
    """

    def __init__(
        self,
        robot: RobotDescription,
        bus: Bus,
        kb: KnowledgeBase,
        *,
        log_dir: Path,
        grace: float = 3.0,
        log_max_bytes: int = 1 << 20,
        log_backups: int = 3,
    ) -> None:
        self.robot = robot
        self.bus = bus
        self.kb = kb
        self.log_dir = log_dir
        self.grace = grace
        self.log_max_bytes = log_max_bytes
        self.log_backups = log_backups
        self._slots = {
            name: _Slot(spec, ComponentState(name, Lifecycle.STOPPED, reason="not started"))
            for name, spec in robot.components.items()
        }
        self._lock = threading.Lock()
        self._listeners: list[Listener] = []
        self._tokens: set[str] = set()  # instances whose liveliness token is there
        self._selector = selectors.DefaultSelector()
        self._wake = os.eventfd(0, os.EFD_CLOEXEC | os.EFD_NONBLOCK)
        self._calls: queue.SimpleQueue[tuple[Callable[[], Any], Future[Any]]] = queue.SimpleQueue()
        self._notices: queue.SimpleQueue[ComponentState | None] = queue.SimpleQueue()
        self._declared: list[Any] = []
        self._running = False
        self._closing = False
        self._loop_thread = threading.Thread(target=self._loop, name="launcher", daemon=True)
        self._notice_thread = threading.Thread(
            target=self._notify, name="launcher-notices", daemon=True
        )

    # --- lifecycle of the launcher ----------------------------------------------------

    def open(self) -> Launcher:
        """Start the launcher's threads and bus subscriptions."""
        self._selector.register(self._wake, selectors.EVENT_READ, self._run_calls)
        self._running = True
        self._loop_thread.start()
        self._notice_thread.start()
        bus = self.bus
        self._declared = [
            bus.watch_alive(keys.component_alive("*", "*"), self._on_token),
            bus.subscribe(keys.component("*", "result"), self._on_result),
            bus.subscribe(keys.component("*", "feedback"), self._on_feedback),
            bus.serve(keys.api("component/achieve"), self._on_achieve),
        ]
        return self

    def close(self) -> None:
        """Stop every component (all at once), then the launcher's threads."""
        if not self._running:
            return
        self._closing = True
        stoppers = [
            threading.Thread(target=self.stop, args=(name,), name=f"stop-{name}")
            for name, slot in self._slots.items()
            if slot.process is not None
        ]
        for thread in stoppers:
            thread.start()
        for thread in stoppers:
            thread.join()
        for entity in self._declared:
            with contextlib.suppress(Exception):
                entity.undeclare()
        self._in_loop(self._finish)
        self._loop_thread.join()
        self._notices.put(None)
        self._notice_thread.join()
        self._selector.close()
        os.close(self._wake)

    def __enter__(self) -> Launcher:
        return self.open()

    def __exit__(self, *exc: object) -> None:
        self.close()

    # --- queries ----------------------------------------------------------------------

    def _slot(self, name: str) -> _Slot:
        slot = self._slots.get(name)
        if slot is None:
            known = ", ".join(self._slots) or "none"
            raise ComponentError(f"no component '{name}' in robot '{self.robot.name}' ({known})")
        return slot

    def kind(self, name: str) -> Kind:
        return self._slot(name).spec.kind

    def state(self, name: str) -> ComponentState:
        return self._slot(name).state

    def states(self) -> list[ComponentState]:
        """The state of every component, in the robot description's order."""
        return [slot.state for slot in self._slots.values()]

    def log_path(self, name: str) -> Path:
        self._slot(name)
        return self.log_dir / f"{name}.log"

    def logs(self, name: str, lines: int = 50) -> list[str]:
        """The last lines of a component's log."""
        return tail(self.log_path(name), lines)

    def add_listener(self, listener: Listener) -> None:
        """Call ``listener(state)`` at every state change of every component.

        Listeners run one after the other on one thread, in the order of the changes;
        they may call the launcher, but hold up the other listeners meanwhile.
        """
        with self._lock:
            self._listeners.append(listener)

    def remove_listener(self, listener: Listener) -> None:
        with self._lock:
            self._listeners.remove(listener)

    # --- starting ---------------------------------------------------------------------

    def start(self, name: str) -> ComponentState:
        """Start a component and wait until it is ready, or failed (a result).

        A component that is already running is left as it is. Waits at most the
        component's start-up timeout (then kills it: FAILED).
        """
        slot = self._slot(name)
        with slot.lock:
            if slot.state.state.is_alive:
                return slot.state
            if self._closing:
                raise ComponentError(f"cannot start '{name}': the launcher is closing")
            deadline = time.monotonic() + slot.spec.startup_timeout
            try:
                process = self._in_loop(lambda: self._spawn(slot))
            except OSError as e:
                program = command(slot.spec.command)[0]
                reason = f"cannot run {program!r}: {e.strerror or e}"
                with self._lock:
                    return self._set(slot, Lifecycle.FAILED, reason=reason)
            failure = self._bring_up(slot, process, deadline)
            with self._lock:
                if not process.exited.is_set() and not failure:
                    process.ready = True
                    return self._set(slot, Lifecycle.READY, pid=process.pid)
            if failure:
                process.failure = failure
                self._terminate(process)
            process.exited.wait()
            return slot.state

    def _bring_up(self, slot: _Slot, process: _Process, deadline: float) -> str:
        """Wait for the process's token, configure and start it; the failure, if any."""
        timeout = slot.spec.startup_timeout
        if not process.woken.wait(max(0.0, deadline - time.monotonic())):
            return f"not ready within {timeout:g} s (no answer)"
        if process.exited.is_set():
            return ""
        name = slot.spec.name
        params = {**slot.spec.params, **self.kb.parameters(name)}
        configure = {"params": params, "achievements": self.kb.achievements(name)}
        for verb, fields in ((Command.CONFIGURE, configure), (Command.START, {})):
            remaining = deadline - time.monotonic()
            if remaining <= 0:
                return f"not ready within {timeout:g} s (no answer to {verb.value})"
            try:
                self._request(name, verb, fields, remaining)
            except BusError as e:
                if process.exited.is_set():
                    return ""
                return f"{verb.value} failed: {e}"
        return ""

    def _spawn(self, slot: _Slot) -> _Process:
        """Start the process (on the launcher thread: children die with it)."""
        spec = slot.spec
        instance = uuid.uuid4().hex[:12]
        env = {
            **os.environ,
            keys.ENV_ROBOT: self.robot.name,
            keys.ENV_COMPONENT: spec.name,
            keys.ENV_ENDPOINT: local_endpoint(self.bus.endpoint),
            keys.ENV_KIND: spec.kind.value,
            keys.ENV_INSTANCE: instance,
            "PYTHONUNBUFFERED": "1",
        }
        logfile = LogFile(
            self.log_dir / f"{spec.name}.log",
            max_bytes=self.log_max_bytes,
            backups=self.log_backups,
        )
        read_end, write_end = os.pipe()
        try:
            popen = spawn(
                spec.command,
                cwd=self.robot.path.parent,
                env=env,
                stdout=write_end,
                own_group=True,
            )
        except OSError:
            os.close(read_end)
            logfile.close()
            raise
        finally:
            os.close(write_end)
        os.set_blocking(read_end, False)
        process = _Process(
            spec.name, instance, popen.pid, popen, os.pidfd_open(popen.pid), read_end, logfile
        )
        logfile.write(f"--- dura: started {spec.name} (pid {popen.pid}) {_now()}\n".encode())
        self._selector.register(process.pidfd, selectors.EVENT_READ, lambda: self._reap(process))
        self._selector.register(read_end, selectors.EVENT_READ, lambda: self._pump(process))
        with self._lock:
            slot.process = process
            self._set(slot, Lifecycle.STARTING, pid=popen.pid)
            self._announce(process)  # in case its token came first
        return process

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
            if slot is not None and slot.process is not None:
                self._announce(slot.process)

    def _announce(self, process: _Process) -> None:
        """Wake the start of a process whose token is there (with ``self._lock`` held)."""
        if process.instance in self._tokens:
            process.announced = True
            process.woken.set()

    # --- stopping ---------------------------------------------------------------------

    def stop(self, name: str, reason: str = "stopped") -> ComponentState:
        """Stop a component and wait until its process is gone; returns its final state.

        The component gets a stop command, then SIGTERM, then SIGKILL (its whole
        process group), each after the grace period.
        """
        slot = self._slot(name)
        with slot.lock:
            with self._lock:
                process = slot.process
                if process is None or process.exited.is_set():
                    return slot.state
                process.stopping = True
                self._set(slot, Lifecycle.STOPPING, pid=process.pid, reason=reason)
            if process.announced:
                with contextlib.suppress(BusError):
                    self._request(name, Command.STOP, {}, self.grace)
            if not process.exited.wait(self.grace):
                self._terminate(process)
            process.exited.wait()
            return slot.state

    def _terminate(self, process: _Process) -> None:
        """SIGTERM to the process group, SIGKILL after the grace period (returns at once
        once it is gone)."""
        signal_group(process.pid, signal.SIGTERM)
        if not process.exited.wait(self.grace):
            log.warning("'%s' ignored SIGTERM: SIGKILL", process.name)
            signal_group(process.pid, signal.SIGKILL)

    def restart(self, name: str) -> ComponentState:
        """Stop (if running) and start again with the component's configuration."""
        self.stop(name, reason="restarting")
        return self.start(name)

    # --- commands ---------------------------------------------------------------------

    def _request(
        self, name: str, verb: Command, fields: Mapping[str, Any], timeout: float
    ) -> dict[str, Any]:
        return self.bus.request(
            keys.component(name, "cmd"), {"cmd": verb.value, **fields}, timeout=timeout
        )

    def command(self, name: str, verb: Command, **fields: Any) -> dict[str, Any]:
        """Send a lifecycle command to a running component and return its reply.

        Raises:
            ComponentError: the component is not running, refused or did not answer.
        """
        slot = self._slot(name)
        if slot.process is None or not slot.process.ready:
            raise ComponentError(f"'{name}' is {slot.state.state.value}, not running")
        try:
            return self._request(name, verb, fields, self.grace)
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
                process = slot.process
                if process is None or process.exited.is_set():
                    return slot.state
                return self._set(slot, after, pid=process.pid)

    def reconfigure(self, name: str, params: Mapping[str, Any]) -> None:
        """Hand changed parameters to a running component."""
        self.command(name, Command.RECONFIGURE, params=dict(params))

    def inject_fault(self, name: str, fault: str | Mapping[str, Any]) -> None:
        """Make a running component misbehave (see :mod:`executive.sdk.fault_injection`)."""
        self.command(name, Command.INJECT_FAULT, fault=fault)

    def send_goal(
        self, name: str, goal: Mapping[str, Any], *, task_id: int | None = None
    ) -> GoalHandle:
        """Send a goal to a ready behavior; its result comes through the handle.

        Raises:
            ComponentError: not a behavior, not ready, or it refused the goal (busy).
        """
        slot = self._slot(name)
        if slot.spec.kind is not Kind.BEHAVIOR:
            raise ComponentError(f"'{name}' is a functionality: it takes no goals")
        handle = GoalHandle(self, name, uuid.uuid4().hex[:12], goal, task_id)
        slot.goals[handle.goal_id] = handle
        try:
            self.command(name, Command.GOAL, goal_id=handle.goal_id, goal=handle.goal)
        except ComponentError:
            del slot.goals[handle.goal_id]
            raise
        return handle

    # --- what components report -------------------------------------------------------

    def _on_result(self, message: Message) -> None:
        try:
            result = GoalResult.from_payload(message.payload)
        except (KeyError, ValueError, TypeError) as e:
            log.warning("malformed result on %s: %s", message.key, e)
            return
        slot = self._slots.get(result.component)
        if slot is not None:
            self._finish_goal(slot, result)

    def _finish_goal(self, slot: _Slot, result: GoalResult) -> None:
        handle = slot.goals.pop(result.goal_id, None)
        if handle is not None and not handle._resolve(result):
            return
        name = slot.spec.name
        task_id = handle.task_id if handle is not None else None
        with self.kb.transaction():
            self.kb.store_return_value(name, result.to_payload(), task_id=task_id)
            self.kb.log_event(
                f"GOAL_RESULT_{result.status.name}",
                name,
                {"goal_id": result.goal_id, "reason": result.reason},
            )
            if result.status is GoalStatus.SUCCEEDED:
                self.kb.clear_achievements(name)

    def _on_feedback(self, message: Message) -> None:
        payload = message.payload
        slot = self._slots.get(str(payload.get("component")))
        feedback = payload.get("feedback")
        if slot is None or not isinstance(feedback, dict):
            return
        handle = slot.goals.get(str(payload.get("goal_id")))
        if handle is not None:
            handle._feedback(feedback)

    def _on_achieve(self, request: dict[str, Any]) -> dict[str, Any]:
        name, key = request.get("component"), request.get("key")
        if not isinstance(name, str) or name not in self._slots:
            raise ComponentError(f"achievement for unknown component {name!r}")
        if not isinstance(key, str) or not key:
            raise ComponentError(f"achievement of '{name}' needs a 'key' string, not {key!r}")
        self.kb.set_achievement(name, key, request.get("value"))
        return {}

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
    ) -> ComponentState:
        """Record and publish a new state (with ``self._lock`` held: keeps the order)."""
        new = ComponentState(
            slot.spec.name, state, pid, exit_code, signum, reason, stamp=time.time()
        )
        slot.state = new
        try:
            self.bus.publish(keys.component(new.component, "state"), new.to_payload())
        except DuraError as e:
            log.warning("cannot publish the state of '%s': %s", new.component, e)
        self._notices.put(new)
        return new

    def _notify(self) -> None:
        """Log every state in the KB and tell the listeners (the notice thread)."""
        while (state := self._notices.get()) is not None:
            payload = state.to_payload()
            del payload["component"], payload["state"]
            try:
                self.kb.log_event(f"COMPONENT_{state.state.name}", state.component, payload)
            except DuraError as e:
                log.warning("cannot log the state of '%s': %s", state.component, e)
            with self._lock:
                listeners = list(self._listeners)
            for listener in listeners:
                _call_safely(listener, state)

    # --- the launcher thread ----------------------------------------------------------

    def _in_loop(self, fn: Callable[[], T]) -> T:
        """Run ``fn`` on the launcher thread and return its result (or raise)."""
        if not self._running:
            raise ComponentError("the launcher is closed")
        outcome: Future[T] = Future()
        self._calls.put((fn, outcome))
        os.eventfd_write(self._wake, 1)
        return outcome.result()

    def _run_calls(self) -> None:
        with contextlib.suppress(BlockingIOError):
            os.eventfd_read(self._wake)
        while True:
            try:
                fn, outcome = self._calls.get_nowait()
            except queue.Empty:
                return
            try:
                outcome.set_result(fn())
            except Exception as e:
                outcome.set_exception(e)

    def _finish(self) -> None:
        self._running = False

    def _loop(self) -> None:
        while self._running:
            for key, _ in self._selector.select():
                try:
                    key.data()
                except Exception:
                    log.exception("the launcher thread failed to handle an event")
        while True:  # calls that came too late
            try:
                _, outcome = self._calls.get_nowait()
            except queue.Empty:
                return
            outcome.set_exception(ComponentError("the launcher is closed"))

    def _pump(self, process: _Process) -> None:
        """Copy what the process wrote into its log file."""
        try:
            while data := os.read(process.pipe, 65536):
                process.log.write(data)
        except BlockingIOError:
            return
        except OSError as e:
            log.warning("cannot read the output of '%s': %s", process.name, e)
        self._close_pipe(process)  # end of file: every writer has gone

    def _close_pipe(self, process: _Process) -> None:
        if process.pipe >= 0:
            self._selector.unregister(process.pipe)
            os.close(process.pipe)
            process.pipe = -1

    def _reap(self, process: _Process) -> None:
        """The process has exited: kill its group, reap it, report (launcher thread)."""
        signal_group(process.pid, signal.SIGKILL)  # pgid == pid; reserved until reaped
        returncode = process.popen.wait()
        self._selector.unregister(process.pidfd)
        os.close(process.pidfd)
        if process.pipe >= 0:
            self._pump(process)
            self._close_pipe(process)
        exit_code, signum = exit_status(returncode)
        how = describe_exit(exit_code, signum)
        slot = self._slots[process.name]
        with self._lock:
            if process.failure:
                state, reason = Lifecycle.FAILED, process.failure
            elif process.stopping:
                state, reason = Lifecycle.STOPPED, slot.state.reason or "stopped"
            elif not process.ready:
                state, reason = Lifecycle.FAILED, f"{how} before it was ready"
            else:
                state, reason = Lifecycle.EXITED, how
            process.log.write(f"--- dura: {state.value}: {how} {_now()}\n".encode())
            process.log.close()
            self._set(
                slot, state, pid=process.pid, exit_code=exit_code, signum=signum, reason=reason
            )
            slot.process = None
            process.exited.set()
            process.woken.set()
        for handle in list(slot.goals.values()):
            status = GoalStatus.CANCELLED if process.stopping else GoalStatus.FAILED
            self._finish_goal(
                slot,
                GoalResult(
                    process.name, handle.goal_id, status, {}, f"'{process.name}' {how}", time.time()
                ),
            )


def _now() -> str:
    return time.strftime("%Y-%m-%d %H:%M:%S")
