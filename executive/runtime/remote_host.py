"""Component processes on other computers, through their host agents (``dura host``).

A :class:`RemoteHost` is a :class:`~executive.runtime.process_host.ProcessHost` whose
processes a host agent starts, signals and reaps (:mod:`executive.runtime.host_agent`);
the requests go over the bus (:mod:`executive.bus.api.hosts`) and the agent publishes
each process's end with its exit code or signal, so the lifecycle gives a remote
component the same states, exit codes and reasons as a local one.

:class:`Hosts` knows every host of the robot and watches their agents' liveliness
tokens (``alive/host/<name>``). A host whose token vanishes (the agent died, its
computer lost power or the network) is lost: each of its processes ends at once, as
far as the executive is concerned, with the reason ``its host '<name>' was lost`` (the
agent, cut off from the executive, ends them itself), the diagnosis engine is told
that they are not available (a ``component`` observation), and the host's components
are unavailable until its agent is back. Both are events of the knowledge base
(``HOST_JOINED``, ``HOST_LOST``), stamped by the executive's clock.
"""

from __future__ import annotations

import functools
import logging
import threading
import time
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any

from executive.bus.api import hosts as api
from executive.bus.api.components import LogQuery
from executive.bus.keys import OBSERVATIONS, host, host_alive
from executive.bus.message import Message
from executive.bus.payloads import GENERAL_OK, NOT_AVAILABLE, ObservationInfo
from executive.bus.session import Bus
from executive.runtime.process_host import (
    ExitHandler,
    Launch,
    LocalHost,
    ProcessHandle,
    ProcessHost,
    Started,
)
from knowledge.description import ComponentSpec, RobotDescription
from knowledge.errors import BusError, ComponentError, DuraError
from knowledge.knowledge_base import KnowledgeBase

log = logging.getLogger("dura.launcher")

# Seconds an agent's vanished token waits for the agent's "stopping": Zenoh may deliver
# a liveliness change ahead of data sent before it, so a clean stop's message may come
# just after it. An agent that says it stops has left at once.
STOPPING_GRACE = 1.0

HostListener = Callable[[str, bool], None]
"""Told ``(host, connected)`` when a host agent joins or is lost."""


@dataclass(eq=False)
class RemoteProcess:
    """A process a host agent started, as the executive knows it."""

    name: str
    instance: str
    pid: int = 0
    program_pid: int | None = None
    started: bool = False  # told to the lifecycle: its end may be told now
    ended: bool = False
    pending: tuple[int | None, int | None, str] | None = None  # an end that came first
    output: tuple[str, ...] = ()  # what it said last, as its host agent read it

    def program(self) -> int:
        return self.program_pid or self.pid

    def finish(self, text: str) -> None:
        """The agent writes the end into its log itself."""


class RemoteHost(ProcessHost):
    """A computer whose host agent runs some of the robot's components.

    Args:
        bus: the executive's bus.
        name: the host's name in the robot description.
        on_exit: told of every process's end (on a bus thread).
    """

    def __init__(self, bus: Bus, name: str, on_exit: ExitHandler) -> None:
        self.bus = bus
        self.name = name
        self._on_exit = on_exit
        self._lock = threading.Lock()
        self._processes: dict[str, RemoteProcess] = {}
        self._logs: dict[str, str] = {}
        self._connected = False
        self.stopping = False  # the agent said it stops: its end is not a loss
        self.on_stopping: Callable[[], None] = lambda: None  # told when it says so
        self._subscribers: list[Any] = []

    @property
    def connected(self) -> bool:
        return self._connected

    def open(self) -> None:
        self._subscribers = [
            self.bus.subscribe(host(self.name, api.EXIT), self._on_exit_message),
            self.bus.subscribe(host(self.name, api.STOPPING), self._on_stopping),
        ]

    def close(self) -> None:
        for subscriber in self._subscribers:
            subscriber.undeclare()
        self._subscribers = []

    def _on_stopping(self, message: Message) -> None:
        self.stopping = True
        self.on_stopping()

    def running(self) -> list[str]:
        """The components of processes started there that have not ended."""
        with self._lock:
            return sorted({p.name for p in self._processes.values() if not p.ended})

    def spawn(self, launch: Launch, started: Started) -> ProcessHandle:
        if not self._connected:
            raise ComponentError(
                f"its host '{self.name}' is not connected (start its agent there: "
                f"dura host ROBOT.yaml --name {self.name})"
            )
        process = RemoteProcess(launch.spec.name, launch.instance)
        with self._lock:
            self._processes[launch.instance] = process
        login = launch.login
        request = api.Spawn(
            launch.spec.name,
            launch.instance,
            run=launch.run_id,
            user=None if login is None else login.user,
            password=None if login is None else login.password,
        )
        try:
            reply = api.spawn(self.name).call(self.bus, request)
        except DuraError as e:
            with self._lock:
                self._processes.pop(launch.instance, None)
            raise ComponentError(f"host '{self.name}': {e}") from e
        process.pid, process.program_pid = reply.pid, reply.program
        self._logs[launch.spec.name] = reply.log
        started(process)
        with self._lock:
            process.started = True
            pending = process.pending
        if pending is not None:
            self._end(process, *pending)
        return process

    def signal(self, process: ProcessHandle, signum: int, *, group: bool = True) -> None:
        if not isinstance(process, RemoteProcess) or process.ended:
            return
        request = api.ProcessSignal(process.instance, signum, group)
        try:
            api.signal(self.name).call(self.bus, request)
        except DuraError as e:  # it ended meanwhile, or the host is gone: its end comes
            log.info("cannot signal '%s' on host '%s': %s", process.name, self.name, e)

    def note(self, process: ProcessHandle, text: str) -> None:
        """The agent writes its own lines (started, the end) into the log there."""

    def log_path(self, component: str) -> str:
        return f"{self.name}:{self._logs.get(component, f'.dura/logs/{component}.log')}"

    def logs(self, component: str, lines: int) -> list[str]:
        try:
            return api.logs(self.name).call(self.bus, LogQuery(component, lines)).lines
        except BusError as e:
            raise ComponentError(f"cannot read the log of '{component}' on host "
                                 f"'{self.name}': {e}") from e  # fmt: skip

    def joined(self) -> None:
        self._connected = True
        self.stopping = False

    def lost(self) -> list[str]:
        """The agent is gone (lost, or stopped if it said so): every process it ran ends;
        the components they were."""
        self._connected = False
        how = f"its host '{self.name}' was {'stopped' if self.stopping else 'lost'}"
        with self._lock:
            processes = list(self._processes.values())
        for process in processes:
            self._end(process, None, None, how)
        return sorted({p.name for p in processes})

    def _on_exit_message(self, message: Message) -> None:
        end = api.ProcessExit.from_payload(message.payload)
        with self._lock:
            process = self._processes.get(end.instance)
        if process is not None:
            process.output = end.output
            self._end(process, end.exit_code, end.signal, "")

    def _end(self, process: RemoteProcess, exit_code: int | None, signum: int | None,
             how: str) -> None:  # fmt: skip
        with self._lock:
            if process.ended:
                return
            if not process.started:
                process.pending = process.pending or (exit_code, signum, how)
                return
            process.ended = True
            self._processes.pop(process.instance, None)
        self._on_exit(process, exit_code, signum, how)


class Hosts:
    """Every computer of the robot: the executive's own and those of its host agents.

    Args:
        robot: where each component is placed (``host:``).
        bus: the executive's bus.
        kb: host events go to its log.
        local: the executive's computer.
        on_exit: told of the end of every remote process.
    """

    def __init__(
        self,
        robot: RobotDescription,
        bus: Bus,
        kb: KnowledgeBase,
        local: LocalHost,
        on_exit: ExitHandler,
    ) -> None:
        self.robot = robot
        self.bus = bus
        self.kb = kb
        self.local = local
        self.remote: Mapping[str, RemoteHost] = {
            name: RemoteHost(bus, name, on_exit) for name in robot.hosts
        }
        self._listeners: list[HostListener] = []
        self._reported: dict[str, set[str]] = {}  # host: components told unavailable
        self._watch: Any = None
        self._tokens = threading.Lock()  # one change of a host's token at a time
        self._vanishing: dict[str, threading.Timer] = {}  # host: its loss, due
        for name, remote in self.remote.items():
            remote.on_stopping = functools.partial(self._stopping, name, remote)

    def open(self) -> None:
        self.local.open()
        for remote in self.remote.values():
            remote.open()
        if self.remote:
            self._watch = self.bus.watch_alive(host_alive("*"), self._on_token)

    def close(self) -> None:
        if self._watch is not None:
            self._watch.undeclare()
            self._watch = None
        with self._tokens:
            for due in self._vanishing.values():
                due.cancel()
            self._vanishing.clear()
        for remote in self.remote.values():
            remote.close()
        self.local.close()

    def of(self, spec: ComponentSpec) -> ProcessHost:
        """The host a component is placed on."""
        return self.local if spec.host is None else self.remote[spec.host]

    def add_listener(self, listener: HostListener) -> None:
        self._listeners.append(listener)

    def remove_listener(self, listener: HostListener) -> None:
        self._listeners.remove(listener)

    def connected(self) -> dict[str, bool]:
        """Each remote host, and whether its agent is there."""
        return {name: remote.connected for name, remote in self.remote.items()}

    def unavailable(self) -> frozenset[str]:
        """The components placed on hosts whose agents are not there."""
        return frozenset(
            name
            for name, spec in self.robot.components.items()
            if spec.host is not None and not self.remote[spec.host].connected
        )

    def _on_token(self, key: str, alive: bool) -> None:
        name = key.rsplit("/", 1)[-1]
        remote = self.remote.get(name)
        if remote is None:
            log.warning("a host agent '%s' announced itself, but robot '%s' places nothing "
                        "there", name, self.robot.name)  # fmt: skip
            return
        with self._tokens:
            due = self._vanishing.pop(name, None)
            if due is not None:
                due.cancel()  # back before its loss was taken: it never left
                if alive:
                    return
            if alive == remote.connected:
                return
            if alive:
                self._changed(name, remote, alive=True)
            elif remote.stopping:
                self._changed(name, remote, alive=False)
            else:  # its "stopping" may still be on its way
                due = threading.Timer(STOPPING_GRACE, self._vanished, (name, remote))
                due.daemon = True
                self._vanishing[name] = due
                due.start()

    def _stopping(self, name: str, remote: RemoteHost) -> None:
        """The agent said it stops: it has left (its token vanishes now or soon)."""
        with self._tokens:
            due = self._vanishing.pop(name, None)
            if due is not None:
                due.cancel()
            if remote.connected:
                self._changed(name, remote, alive=False)

    def _vanished(self, name: str, remote: RemoteHost) -> None:
        with self._tokens:
            if self._vanishing.pop(name, None) is None:
                return  # cancelled meanwhile
            self._changed(name, remote, alive=False)

    def _changed(self, name: str, remote: RemoteHost, *, alive: bool) -> None:
        """A host's agent joined, or left (stopped if it said so, else lost)."""
        if alive:
            remote.joined()
            self._report(name, self._reported.pop(name, set()), available=True)
            self.kb.log_event("HOST_JOINED", name, {"components": self.robot.placed_on(name)})
        else:
            stopped = remote.stopping
            lost = remote.lost()
            self.kb.log_event("HOST_STOPPED" if stopped else "HOST_LOST", name,
                              {"components": lost})  # fmt: skip
            how = "stopped (its agent said so)" if stopped else "lost (its agent's token vanished)"
            log.warning("host '%s' %s: %s", name, how, ", ".join(lost) or "nothing ran there")
            self._reported.setdefault(name, set()).update(lost)
            self._report(name, set(lost), available=False, stopped=stopped)
        for listener in list(self._listeners):
            try:
                listener(name, alive)
            except Exception:
                log.exception("host listener %r failed", listener)

    def _report(
        self, name: str, components: set[str], *, available: bool, stopped: bool = False
    ) -> None:
        """Tell the diagnosis engine whether the components of a host are there."""
        gone = "was stopped" if stopped else "was lost"
        for component in sorted(components):
            message = f"its host '{name}' {'is back' if available else gone}"
            info = ObservationInfo(
                "component",
                (component,),
                GENERAL_OK if available else NOT_AVAILABLE,
                message,
                stamp=time.time(),
            )
            try:
                self.bus.publish(OBSERVATIONS, info.to_payload())
            except DuraError as e:
                log.warning("cannot report '%s' to the diagnosis engine: %s", component, e)
