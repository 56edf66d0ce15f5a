"""Where a component's process runs: on this computer, or on another one's host agent.

The lifecycle (:mod:`executive.runtime.component_lifecycle`) decides what a process's start and
end mean; a :class:`ProcessHost` only starts processes, signals them and tells of their
ends, with the same exit codes and signals wherever they ran. :class:`LocalHost` forks
them here (:mod:`executive.runtime.processes`); a remote host
(:mod:`executive.runtime.remote_host`) asks the host agent of another computer over
the bus. Both build a component's environment the same way
(:func:`component_environment`), each with the endpoint its components reach the
executive at.
"""

from __future__ import annotations

import contextlib
import os
from abc import ABC, abstractmethod
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Protocol

from executive.bus import keys, security
from executive.bus.security import Login
from executive.runtime.logfile import tail
from executive.runtime.processes import ComponentProcess, ProcessThread
from executive.runtime.ros2_launch import launch_program
from executive.runtime.run_lock import ENV_RUN
from knowledge.description import ComponentSpec, RobotDescription
from knowledge.errors import ComponentError


class ProcessHandle(Protocol):
    """One started component process, wherever it runs."""

    name: str
    pid: int  # its supervisor's, on its host
    output: tuple[str, ...]  # once it ended: what it said last (its exception)

    def program(self) -> int:
        """The component's own process (its supervisor's pid until it is known)."""
        ...

    def finish(self, text: str) -> None:
        """Write the last line of dura's own into its log (where the log is here)."""
        ...


ExitHandler = Callable[[ProcessHandle, "int | None", "int | None", str], None]
"""Told ``(process, exit_code, signal, how)`` once a process has ended; ``how`` says how it
ended when no exit code or signal can (its host was lost), else it is empty."""

Started = Callable[[ProcessHandle], None]
"""Told of a process as soon as it exists, before its end can be told."""


@dataclass(frozen=True)
class Launch:
    """What a host needs to start a component: which, the instance that names its
    liveliness token, its own bus login and the executive's run mark."""

    spec: ComponentSpec
    instance: str
    login: Login | None = None
    run_id: str | None = None


def component_environment(
    robot: RobotDescription,
    launch: Launch,
    endpoint: str,
    base: Mapping[str, str] | None = None,
) -> tuple[list[str], dict[str, str]]:
    """The argv and environment of a component process that reaches the executive at
    ``endpoint`` (a ROS 2 program runs under its host, :mod:`executive.runtime.ros2_host`);
    ``base`` is the environment it inherits (default: this process's)."""
    spec = launch.spec
    env = {
        **(os.environ if base is None else base),
        keys.ENV_ROBOT: robot.name,
        keys.ENV_COMPONENT: spec.name,
        keys.ENV_ENDPOINT: endpoint,
        keys.ENV_KIND: spec.kind.value,
        keys.ENV_INSTANCE: launch.instance,
    }
    for name in (security.ENV_USER, security.ENV_PASSWORD):
        env.pop(name, None)  # never the starter's own login
    if launch.run_id is not None:  # marks the tree as this executive's (see run_lock)
        env[ENV_RUN] = launch.run_id
    if launch.login is not None:  # its own user: it may do only a component's part
        env[security.ENV_USER] = launch.login.user
        env[security.ENV_PASSWORD] = launch.login.password
    argv, extra = launch_program(robot, spec)
    env.update(extra)
    return argv, env


class ProcessHost(ABC):
    """Starts, signals and reaps component processes on one computer.

    ``name`` is the host's name in the robot description (empty: the executive's own).
    """

    name: str = ""

    @property
    def connected(self) -> bool:
        """Whether processes can be started there now."""
        return True

    @abstractmethod
    def open(self) -> None:
        """Start what the host needs (threads, subscriptions)."""

    @abstractmethod
    def close(self) -> None:
        """Release it (after every process has ended)."""

    @abstractmethod
    def spawn(self, launch: Launch, started: Started) -> ProcessHandle:
        """Start a component under its supervisor; ``started`` is told before its end can
        be.

        Raises:
            OSError: its program cannot be run here.
            ComponentError: the host cannot start it (not connected, refused).
        """

    @abstractmethod
    def signal(self, process: ProcessHandle, signum: int, *, group: bool = True) -> None:
        """Signal a process's group (or only its supervisor) unless it has ended."""

    @abstractmethod
    def note(self, process: ProcessHandle, text: str) -> None:
        """A line of dura's own in the process's log (where the host keeps one)."""

    @abstractmethod
    def log_path(self, component: str) -> str:
        """Where a component's log is (on a remote host: ``host:path``)."""

    @abstractmethod
    def logs(self, component: str, lines: int) -> list[str]:
        """The last lines of a component's log."""


class LocalHost(ProcessHost):
    """The executive's own computer: processes forked by the launcher thread.

    Args:
        robot: commands run in its description's folder.
        endpoint: where a local child reaches the executive.
        processes: the launcher thread (its exits go where it was told).
    """

    def __init__(self, robot: RobotDescription, endpoint: str, processes: ProcessThread) -> None:
        self.robot = robot
        self.endpoint = endpoint
        self.processes = processes

    def open(self) -> None:
        self.processes.open()

    def close(self) -> None:
        self.processes.close()

    def spawn(self, launch: Launch, started: Started) -> ProcessHandle:
        def fork() -> ComponentProcess:  # on the launcher thread: its exit waits for us
            argv, env = component_environment(self.robot, launch, self.endpoint)
            cwd = self.robot.path.parent
            process = self.processes.fork(launch.spec.name, argv, cwd=cwd, env=env)
            started(process)
            return process

        return self.processes.call(fork)

    def signal(self, process: ProcessHandle, signum: int, *, group: bool = True) -> None:
        if not isinstance(process, ComponentProcess):
            raise ComponentError(f"'{process.name}' was not started on this computer")
        self.processes.signal(process, signum, group=group)

    def note(self, process: ProcessHandle, text: str) -> None:
        if not isinstance(process, ComponentProcess):
            return

        def note() -> None:
            if not process.reaped:
                process.note(text)

        with contextlib.suppress(ComponentError):  # the launcher closes
            self.processes.call(note)

    def log_file(self, component: str) -> Path:
        return self.processes.log_path(component)

    def log_path(self, component: str) -> str:
        return str(self.log_file(component))

    def logs(self, component: str, lines: int) -> list[str]:
        return tail(self.log_file(component), lines)
