"""A robot run by a real ``dura run`` process, driven over the bus: for tests and the demo.

:class:`RobotProcess` starts the executive of a robot description in a folder of its
own (knowledge base, logs, free loopback endpoint) and waits until it answers; what a
test of a domain then asks of it (submit goals, wait for their outcome, inject faults
into components, read the event log and the facts) is its
:class:`~executive.testing.client.RobotClient` side. It can also kill the executive
(SIGKILL) and start it again on the same knowledge base, to test recovery.
:class:`ServiceGroupProcess` runs a group of services in a process of its own beside it.

The pytest plugin :mod:`executive.testing` hands it to tests as the ``dura_robot``
fixture.
"""

from __future__ import annotations

import contextlib
import itertools
import os
import signal
import socket
import subprocess
import sys
import threading
import time
from abc import abstractmethod
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any, Self

import yaml

from executive.bus import security
from executive.bus.clock import SCALE_VARIABLE, Clock
from executive.bus.keys import EXECUTIVE_ALIVE, service_alive
from executive.bus.security import Login
from executive.bus.session import Bus
from executive.testing.client import INJECT_TIMEOUT, GoalEnded, RobotClient, WaitTimedOut
from knowledge.description import RobotDescription
from knowledge.errors import BusError, DuraError
from knowledge.robot import load_robot
from knowledge.yamlsource import load as load_yaml

__all__ = [  # GoalEnded, WaitTimedOut and INJECT_TIMEOUT live in the client; named here too
    "INJECT_TIMEOUT",
    "START_TIMEOUT",
    "ExecutiveProcess",
    "GoalEnded",
    "RobotProcess",
    "ServiceGroupProcess",
    "WaitTimedOut",
    "free_endpoint",
    "robot_variant",
    "terminate",
]

START_TIMEOUT = 60.0  # seconds for the executive to answer after it was started


def free_endpoint() -> str:
    """A loopback TCP endpoint nobody listens on (yet)."""
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return f"tcp/127.0.0.1:{s.getsockname()[1]}"


def robot_variant(description: Path, folder: Path, changes: Mapping[str, Any]) -> Path:
    """Write a copy of a robot description into ``folder`` with ``changes`` merged in.

    ``changes`` is nested like the YAML, e.g. ``{"behaviors": {"move_to": {"max_restarts":
    0}}}``; a ``None`` value removes a key. The files beside the original (components,
    problem, integrity rules) are linked into ``folder`` and the domain path is made
    absolute, so the copy runs like the original. Returns the copy's path.
    """
    description = Path(description).resolve()
    folder = Path(folder).resolve()
    folder.mkdir(parents=True, exist_ok=True)
    data = load_yaml(description)  # the safe reader, as dura reads the description
    data["domain"] = str((description.parent / data["domain"]).resolve())
    _merge(data, changes)
    for entry in description.parent.iterdir():
        target = folder / entry.name
        if entry != description and not target.exists() and not entry.name.startswith("."):
            target.symlink_to(entry)
    copy = folder / description.name
    copy.write_text(yaml.safe_dump(data, sort_keys=False), encoding="utf-8")
    return copy


def _merge(into: dict[str, Any], changes: Mapping[str, Any]) -> None:
    for key, value in changes.items():
        if value is None:
            into.pop(key, None)
        elif isinstance(value, Mapping) and isinstance(into.get(key), dict):
            _merge(into[key], value)
        else:
            into[key] = value


def terminate(process: subprocess.Popen[Any], timeout: float) -> None:
    """End a process as Ctrl-C does (SIGTERM), SIGKILL it if it is still there after
    ``timeout`` seconds, and wait for it."""
    if process.poll() is None:
        process.send_signal(signal.SIGTERM)
        try:
            process.wait(timeout)
        except subprocess.TimeoutExpired:
            process.kill()
            process.wait()


class ExecutiveProcess(RobotClient):
    """A child process that serves the executive's bus API: an executive
    (:class:`RobotProcess`) or a fleet's high level
    (:class:`~executive.testing.fleet.FleetProcess`). Its start, stop and kill, its
    liveliness token and its output; what a test asks of it is
    :class:`~executive.testing.client.RobotClient`'s."""

    robot: RobotDescription
    folder: Path
    endpoint: str
    output: Path

    def __init__(self) -> None:
        self._process: subprocess.Popen[bytes] | None = None
        self._bus: Bus | None = None
        self._running = threading.Event()  # its liveliness token is there

    @property
    @abstractmethod
    def what(self) -> str:
        """How messages name it: ``the executive of 'usecase'``."""

    @abstractmethod
    def start(self, timeout: float = START_TIMEOUT) -> None:
        """Start the process and wait until every service of it runs."""

    def __enter__(self) -> Self:
        self.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self.stop()

    def _started(self, probe: str, timeout: float) -> int | None:
        """Wait until the process just started answers ``probe`` and its liveliness token
        is there (every service started, not only the API); returns ``None``, or its
        exit code if it ended first.

        Raises:
            DuraError: it did not answer within ``timeout`` seconds (it is stopped).
        """
        process = self._process
        if process is None:
            raise DuraError(f"{self.what} was not started")
        deadline = time.monotonic() + timeout
        while True:
            if process.poll() is not None:
                self._close()
                return process.returncode
            try:
                if self._bus is None:
                    self._bus = Bus(
                        self.robot.name, name="harness", endpoint=self.endpoint, login=self.login()
                    )
                    self._bus.watch_alive(EXECUTIVE_ALIVE, self._on_alive)
                self.request(probe, timeout=2.0)
                if self._running.wait(0.1):
                    return None
                raise BusError(f"{self.what} is starting")
            except BusError:
                if time.monotonic() > deadline:
                    self.stop()
                    raise DuraError(
                        f"{self.what} did not answer within {timeout:g} s:\n{self.log_tail()}"
                    ) from None
                time.sleep(0.1)

    def login(self) -> Login | None:
        """The operator's login to its bus (the credentials it wrote in its folder)."""
        return security.find_login(self.robot.name, security.OPERATOR, [self.folder])

    def _on_alive(self, key: str, alive: bool) -> None:
        if alive:
            self._running.set()
        else:
            self._running.clear()

    @property
    def pid(self) -> int:
        """The process's id."""
        if self._process is None:
            raise DuraError(f"{self.what} does not run")
        return self._process.pid

    @property
    def running(self) -> bool:
        return self._process is not None and self._process.poll() is None

    def stop(self, timeout: float = 30.0) -> int | None:
        """Stop it as Ctrl-C does (SIGTERM); returns its exit code."""
        process = self._process
        if process is None:
            return None
        terminate(process, timeout)
        self._close()
        return process.returncode

    def kill(self) -> None:
        """SIGKILL it, as a crash would (an executive's components end by themselves)."""
        process = self._process
        if process is not None:
            process.kill()
            process.wait()
        self._close()

    def _close(self) -> None:
        if self._bus is not None:
            self._bus.close()
        self._bus, self._process = None, None
        self._running.clear()

    def log_tail(self, lines: int = 20) -> str:
        with contextlib.suppress(OSError):
            return "\n".join(self.output.read_text(errors="replace").splitlines()[-lines:])
        return ""

    @property
    def bus(self) -> Bus:
        if self._bus is None:
            raise DuraError(f"{self.what} does not run")
        return self._bus


class RobotProcess(ExecutiveProcess):
    """The executive of one robot, as a child process (see the module docstring); the
    helpers a test calls on it are :class:`~executive.testing.client.RobotClient`'s.

    Args:
        description: the robot description (YAML).
        folder: where the knowledge base, the logs and the executive's output go.
        endpoint: where the executive listens (default: a free loopback port).
        run_args: more arguments of ``dura run`` (e.g. ``["--record", "run.mcap"]``).
        time_scale: robot time runs this many times faster than the wall clock, in the
            executive and its components (``DURA_TIME_SCALE``); timeouts given to the
            ``wait_*`` methods stay wall-clock seconds.
    """

    def __init__(
        self,
        description: Path,
        folder: Path,
        endpoint: str | None = None,
        run_args: Sequence[str] = (),
        *,
        time_scale: float | None = None,
    ) -> None:
        self.clock = Clock(time_scale) if time_scale is not None else Clock.from_environment()
        self.description = Path(description).resolve()
        self.robot = load_robot(self.description)
        self.folder = Path(folder)
        self.folder.mkdir(parents=True, exist_ok=True)
        self.endpoint = endpoint or free_endpoint()
        self._own_endpoint = endpoint is None  # chosen here: another may be chosen on a clash
        self.run_args = tuple(run_args)
        without = {b for a, b in itertools.pairwise(self.run_args) if a == "--without"}
        # what answers once the executive's services run: status needs the task executor
        # and the high level, each of which may run in a process of its own
        self._probe = (
            "task/list" if "planning" in without else "goal/list" if "tasks" in without
            else "status"
        )  # fmt: skip
        self.kb_path = self.folder / f"{self.robot.name}.db"
        self.output = self.folder / "executive.log"
        super().__init__()

    @property
    def what(self) -> str:
        return f"the executive of '{self.robot.name}'"

    def start(self, timeout: float = START_TIMEOUT, *, tries: int = 3) -> None:
        """Start the executive and wait until every service of it runs (its liveliness
        token is there: the bus API answers a little earlier)."""
        if self._process is not None:
            raise DuraError(f"the executive of '{self.robot.name}' runs already")
        argv = ["--endpoint", self.endpoint, "--db", str(self.kb_path)]
        argv += ["--log-dir", str(self.folder / "logs"), "--grace", "1", *self.run_args]
        self._process = self.run(argv, self.output)
        code = self._started(self._probe, timeout)
        if code is None:
            return
        if self._own_endpoint and "Address already in use" in self.log_tail(3) and tries:
            # another process took the free port between our look and its bind
            self.endpoint = free_endpoint()
            self.start(timeout, tries=tries - 1)
            return
        raise DuraError(f"the executive exited with {code} at start:\n{self.log_tail()}")

    def run(self, args: Sequence[str], output: Path) -> subprocess.Popen[bytes]:
        """Start ``dura run`` of this robot with ``args`` in its folder, on its clock,
        its output appended to ``output``."""
        argv = [sys.executable, "-m", "executive.cli", "run", str(self.description), *args]
        env = {**os.environ, **self.clock.environment()}
        if not self.clock.scaled:
            env.pop(SCALE_VARIABLE, None)
        with output.open("ab") as out:
            return subprocess.Popen(
                argv, cwd=self.folder, stdout=out, stderr=subprocess.STDOUT, env=env
            )

    @property
    def credentials(self) -> Path:
        """The robot's bus credentials, as ``dura`` commands run elsewhere need them
        (``DURA_BUS_CREDENTIALS``)."""
        return security.credentials_file(self.folder, self.robot.name)

    def environment(self) -> dict[str, str]:
        """The environment for a ``dura`` command run against this robot from any folder."""
        return {**os.environ, security.ENV_CREDENTIALS: str(self.credentials)}


class ServiceGroupProcess:
    """A group of services in a process of its own (``dura run --only GROUP``) beside a
    :class:`RobotProcess` that runs ``--without GROUP``; it runs once its liveliness
    token is there. Its output goes to ``<group>.log`` in the robot's folder.
    """

    def __init__(self, robot: RobotProcess, group: str) -> None:
        self.robot = robot
        self.group = group
        self.output = robot.folder / f"{group}.log"
        self._process: subprocess.Popen[bytes] | None = None

    def __enter__(self) -> ServiceGroupProcess:
        self.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self.stop()

    def start(self, timeout: float = START_TIMEOUT) -> None:
        """Start the process and wait until its services run."""
        robot = self.robot
        argv = ["--only", self.group, "--endpoint", robot.endpoint, "--db", str(robot.kb_path)]
        self._process = robot.run(argv, self.output)
        deadline = time.monotonic() + timeout
        while not robot.bus.alive(service_alive(self.group), timeout=1.0):
            if self._process.poll() is not None or time.monotonic() > deadline:
                self.stop()
                raise DuraError(f"the {self.group} process did not run:\n{self.log_tail()}")

    @property
    def pid(self) -> int:
        """The process's id."""
        if self._process is None:
            raise DuraError(f"the {self.group} process does not run")
        return self._process.pid

    def stop(self, timeout: float = 30.0) -> int | None:
        """Stop the process as Ctrl-C does (SIGTERM); returns its exit code."""
        process, self._process = self._process, None
        if process is None:
            return None
        terminate(process, timeout)
        return process.returncode

    def log_tail(self, lines: int = 20) -> str:
        with contextlib.suppress(OSError):
            return "\n".join(self.output.read_text(errors="replace").splitlines()[-lines:])
        return ""
