"""The host agent (``dura host``): the executive's launcher on another computer.

A robot's components may run on several computers (``host: NAME`` in the robot
description). On each computer but the executive's, one agent connects to the
executive's bus as the user ``host.<name>``; while the executive is there (its
liveliness token ``alive/executive``), the agent serves the requests of
:mod:`executive.bus.api.hosts` and declares its own token ``alive/host/<name>``. It
starts only the components the description places on it, each under its supervisor in
a process group of its own (:mod:`executive.runtime.processes`, as the executive does),
keeps their logs here, publishes each end with its exit code or signal, and tells the
resource monitor of its processes.

When the executive vanishes (it stopped or died, or the network between them broke),
the agent ends every component it runs, as the executive's own children die with it,
and withdraws its token; when the executive is back, it joins again. A component is
never started twice: a spawn for a component the agent still runs ends the old process
first. If the agent itself dies, its components' supervisors end their trees.
"""

from __future__ import annotations

import contextlib
import logging
import os
import signal
import threading
import time
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any, Protocol

from executive.bus import keys, security
from executive.bus.api import hosts as api
from executive.bus.api.components import LogQuery, LogReply
from executive.bus.security import Login
from executive.bus.session import Bus, connect_when_there
from executive.bus.verb import Empty
from executive.runtime.logfile import tail
from executive.runtime.process_host import Launch, component_environment
from executive.runtime.processes import ComponentProcess, ProcessThread
from executive.runtime.spawn import command, describe_exit
from knowledge.description import RobotDescription
from knowledge.errors import ComponentError, DuraError

log = logging.getLogger("dura.host")

PROGRAM_WAIT = 0.5  # seconds to wait for the program's pid below its supervisor


class Tracker(Protocol):
    """What the agent tells the resource monitor of its processes."""

    def start(self) -> None: ...

    def stop(self) -> None: ...

    def track(self, name: str, pid: int) -> None: ...

    def untrack(self, name: str) -> None: ...


class HostAgent:
    """Serves one host of a robot (see the module docstring).

    Args:
        robot: the robot; commands run in its description's folder here.
        name: the host's name in the description.
        endpoint: the executive's endpoint, as this computer reaches it (its components
            connect there too).
        login: the host's own bus login (``host.<name>``).
        log_dir: where ``<component>.log`` files go.
        grace: seconds a component gets to stop, at each step.
        tracker: makes the resource monitor of this host's processes, once on the bus.
        lease: seconds of silence after which the link to the executive counts as lost.
        say: told one line at each change (joined, lost), for the operator.
    """

    def __init__(
        self,
        robot: RobotDescription,
        name: str,
        *,
        endpoint: str,
        login: Login | None,
        log_dir: Path,
        grace: float = 3.0,
        tracker: Callable[[Bus], Tracker] | None = None,
        lease: float | None = None,
        say: Callable[[str], None] = lambda line: None,
    ) -> None:
        if name not in robot.hosts:
            hosts = ", ".join(robot.hosts) or "none"
            raise ComponentError(
                f"robot '{robot.name}' places no component on host '{name}' (its hosts: {hosts})"
            )
        self.robot = robot
        self.name = name
        self.endpoint = endpoint
        self.login = login
        self.grace = grace
        self.lease = lease
        self.components = robot.placed_on(name)
        self._say = say
        self._make_tracker = tracker
        self._tracker: Tracker | None = None
        self._env = {k: v for k, v in os.environ.items() if k != security.ENV_CREDENTIALS}
        self._lock = threading.Condition()
        self._running: dict[str, ComponentProcess] = {}  # by instance
        self._executive = False  # its token is there
        self._joined = False  # our token is there: we serve
        self._changed = threading.Event()
        self._token: Any = None
        self._declared: list[Any] = []
        self.bus: Bus | None = None
        self.processes = ProcessThread(
            log_dir, log_max_bytes=1 << 20, log_backups=3, on_exit=self._exited, grace=grace
        )

    # --- running --------------------------------------------------------------------------

    def run(self, stop: threading.Event) -> None:
        """Serve until ``stop`` is set: reach the executive (again and again), join while
        it is there, end every component whenever it is not."""
        bus = self._connect(stop)
        if bus is None:
            return
        self.processes.open()
        try:
            if self._make_tracker is not None:
                self._tracker = self._make_tracker(bus)
                self._tracker.start()
            self._declared = [
                api.spawn(self.name).serve(bus, self._spawn),
                api.signal(self.name).serve(bus, self._signal),
                api.logs(self.name).serve(bus, self._logs),
                bus.watch_alive(keys.EXECUTIVE_ALIVE, self._on_executive),
            ]
            while not stop.is_set():
                self._changed.wait(0.5)
                self._changed.clear()
                self._follow()
        finally:
            self._leave("the host agent stops", clean=True)
            for entity in self._declared:
                with contextlib.suppress(Exception):
                    entity.undeclare()
            self.processes.close()
            if self._tracker is not None:
                self._tracker.stop()
            bus.close()

    def _connect(self, stop: threading.Event) -> Bus | None:
        """The bus, once the executive's endpoint answers (``None``: stopped first)."""

        def connect() -> Bus:
            return Bus(self.robot.name, name=security.host_user(self.name),
                       endpoint=self.endpoint, login=self.login, lease=self.lease)  # fmt: skip

        self.bus = connect_when_there(connect, self.endpoint, stop, self._say)
        return self.bus

    def _on_executive(self, key: str, alive: bool) -> None:
        self._executive = alive
        self._changed.set()

    def _follow(self) -> None:
        """Join while the executive is there; leave (ending everything) when it is not."""
        if self._executive and not self._joined:
            bus = self.bus
            if bus is None:
                return
            others = bus.alive(keys.host_alive(self.name))
            if others:  # another agent serves this host: never two of one component
                self._say(f"another agent serves host '{self.name}' already; waiting")
                return
            with self._lock:
                self._joined = True
            self._token = bus.declare_alive(keys.host_alive(self.name))
            self._say(f"joined: serves {', '.join(self.components)}")
        elif not self._executive and self._joined:
            self._leave("the executive was lost")

    def _leave(self, why: str, *, clean: bool = False) -> None:
        """Withdraw the token and end every component (SIGTERM, then their trees);
        ``clean``: tell the executive first that this agent stops (it is not lost)."""
        with self._lock:
            was = self._joined
            self._joined = False
        if clean and was and self.bus is not None:
            with contextlib.suppress(DuraError):
                self.bus.publish(keys.host(self.name, api.STOPPING), {})
        if self._token is not None:
            with contextlib.suppress(Exception):
                self._token.undeclare()
            self._token = None
        ended = self.end_all()
        if was:
            self._say(f"left ({why}): ended {', '.join(ended) or 'nothing'}")

    def end_all(self) -> list[str]:
        """End every process this agent runs and wait until they are reaped; their names."""
        with self._lock:
            processes = list(self._running.values())
        for sig, group in ((signal.SIGTERM, True), (signal.SIGUSR1, False),
                           (signal.SIGKILL, True)):  # fmt: skip
            with self._lock:
                left = [p for p in processes if not p.reaped]
            for process in left:
                with contextlib.suppress(ComponentError):
                    self.processes.signal(process, sig, group=group)
            deadline = time.monotonic() + self.grace
            with self._lock:
                while any(not p.reaped for p in processes) and time.monotonic() < deadline:
                    self._lock.wait(max(0.0, deadline - time.monotonic()))
                if all(p.reaped for p in processes):
                    break
        return sorted({p.name for p in processes})

    # --- the requests -----------------------------------------------------------------------

    def _spawn(self, request: api.Spawn) -> api.Spawned:
        spec = self.robot.components.get(request.component)
        if spec is None or spec.host != self.name:
            raise ComponentError(
                f"robot '{self.robot.name}' places no component '{request.component}' on "
                f"host '{self.name}' (here: {', '.join(self.components)})"
            )
        with self._lock:
            if not self._joined:
                raise ComponentError(f"host '{self.name}' does not serve (no executive)")
            stale = [p for p in self._running.values() if p.name == spec.name]
        for process in stale:  # the executive thinks it ended: it must not run twice
            log.warning("'%s' (pid %d) still runs: killed before its new start", spec.name,
                        process.pid)  # fmt: skip
            self.processes.signal(process, signal.SIGKILL)
        login = None
        if request.user is not None and request.password is not None:
            login = Login(request.user, request.password)
        launch = Launch(spec, request.instance, login, request.run)
        children = self.endpoint

        def fork() -> ComponentProcess:
            argv, env = component_environment(self.robot, launch, children, base=self._env)
            process = self.processes.fork(spec.name, argv, cwd=self.robot.path.parent, env=env)
            with self._lock:
                self._running[request.instance] = process
            return process

        try:
            process = self.processes.call(fork)
        except OSError as e:
            argv0 = command(spec.command)[0] if spec.command else spec.name
            raise ComponentError(f"cannot run {argv0!r}: {e.strerror or e}") from e
        program = self._program(process)
        if self._tracker is not None and program is not None:
            self._tracker.track(spec.name, program)
        return api.Spawned(process.pid, str(self.processes.log_path(spec.name)), program)

    def _program(self, process: ComponentProcess) -> int | None:
        """The program's pid below its supervisor, once forked (``None``: not yet)."""
        deadline = time.monotonic() + PROGRAM_WAIT
        while time.monotonic() < deadline and not process.reaped:
            pid = process.program()
            if pid != process.pid:
                return pid
            time.sleep(0.005)
        return None

    def _signal(self, request: api.ProcessSignal) -> Empty:
        with self._lock:
            process = self._running.get(request.instance)
        if process is not None:
            self.processes.signal(process, request.signal, group=request.group)
        return Empty()

    def _logs(self, request: LogQuery) -> LogReply:
        if request.name not in self.components:
            raise ComponentError(f"host '{self.name}' runs no component '{request.name}'")
        path = self.processes.log_path(request.name)
        return LogReply(request.name, str(path), tail(path, request.lines))

    def _exited(self, process: ComponentProcess, exit_code: int | None, signum: int | None) -> None:
        """A process was reaped (on the launcher thread): tell the executive."""
        process.finish(describe_exit(exit_code, signum))
        with self._lock:
            instance = next((i for i, p in self._running.items() if p is process), "")
            self._running.pop(instance, None)
            again = any(p.name == process.name for p in self._running.values())
            self._lock.notify_all()
        if self._tracker is not None and not again:
            self._tracker.untrack(process.name)
        end = api.ProcessExit(process.name, instance or "?", process.pid, exit_code, signum,
                              stamp=time.time(), output=process.output)  # fmt: skip
        bus = self.bus
        if bus is not None:
            with contextlib.suppress(Exception):  # no executive: it learnt of the end anyway
                bus.publish(keys.host(self.name, api.EXIT), end.to_payload())

    def running(self) -> Mapping[str, int]:
        """The components running here, with their supervisors' pids."""
        with self._lock:
            return {p.name: p.pid for p in self._running.values()}
