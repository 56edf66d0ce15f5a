"""A robot run by a real ``dura run`` process, driven over the bus: for tests and the demo.

:class:`RobotProcess` starts the executive of a robot description in a folder of its
own (knowledge base, logs, free loopback endpoint), waits until it answers, and offers
what a test of a domain needs: submit goals, wait for their outcome, inject faults into
components, read the event log and the facts. It can also kill the executive (SIGKILL)
and start it again on the same knowledge base, to test recovery.

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
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import yaml

from executive.bus import security
from executive.bus.api import planning
from executive.bus.api.components import COMPONENT_INJECT, COMPONENT_LIST, Injection
from executive.bus.clock import SCALE_VARIABLE, Clock
from executive.bus.keys import EXECUTIVE_ALIVE, api, service_alive
from executive.bus.security import Login
from executive.bus.session import Bus
from executive.bus.states import Lifecycle
from knowledge.errors import BusError, DuraError
from knowledge.records import GoalState
from knowledge.robot import load_robot

START_TIMEOUT = 60.0  # seconds for the executive to answer after it was started
INJECT_TIMEOUT = 30.0  # seconds a fault injection waits for its component to run


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
    data = yaml.safe_load(description.read_text(encoding="utf-8"))
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


class GoalEnded(AssertionError):
    """A goal ended other than expected, or did not end in time (a test failure)."""


class WaitTimedOut(AssertionError):
    """What a test waited for did not happen in time (a test failure)."""


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


class RobotProcess:
    """The executive of one robot, as a child process (see the module docstring).

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
        self._process: subprocess.Popen[bytes] | None = None
        self._bus: Bus | None = None
        self._running = threading.Event()  # the executive's liveliness token is there

    # --- lifecycle -----------------------------------------------------------------------

    def __enter__(self) -> RobotProcess:
        self.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self.stop()

    def start(self, timeout: float = START_TIMEOUT, *, tries: int = 3) -> None:
        """Start the executive and wait until every service of it runs (its liveliness
        token is there: the bus API answers a little earlier)."""
        if self._process is not None:
            raise DuraError(f"the executive of '{self.robot.name}' runs already")
        argv = ["--endpoint", self.endpoint, "--db", str(self.kb_path)]
        argv += ["--log-dir", str(self.folder / "logs"), "--grace", "1", *self.run_args]
        self._process = self.run(argv, self.output)
        deadline = time.monotonic() + timeout
        while True:
            if self._process.poll() is not None:
                code = self._process.returncode
                self._close()
                if self._own_endpoint and "Address already in use" in self.log_tail(3) and tries:
                    # another process took the free port between our look and its bind
                    self.endpoint = free_endpoint()
                    self.start(timeout, tries=tries - 1)
                    return
                raise DuraError(f"the executive exited with {code} at start:\n{self.log_tail()}")
            try:
                if self._bus is None:
                    self._bus = Bus(
                        self.robot.name, name="harness", endpoint=self.endpoint, login=self.login()
                    )
                    self._bus.watch_alive(EXECUTIVE_ALIVE, self._on_alive)
                self.request(self._probe, timeout=2.0)
                if self._running.wait(0.1):  # every service started, not only the API
                    return
                raise BusError("the executive is starting")
            except BusError:
                if time.monotonic() > deadline:
                    self.stop()
                    raise DuraError(
                        f"the executive did not answer within {timeout:g} s:\n{self.log_tail()}"
                    ) from None
                time.sleep(0.1)

    @property
    def pid(self) -> int:
        """The executive's process id."""
        if self._process is None:
            raise DuraError(f"the executive of '{self.robot.name}' does not run")
        return self._process.pid

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

    def _on_alive(self, key: str, alive: bool) -> None:
        if alive:
            self._running.set()
        else:
            self._running.clear()

    def stop(self, timeout: float = 30.0) -> int | None:
        """Stop the executive as Ctrl-C does (SIGTERM); returns its exit code."""
        process = self._process
        if process is None:
            return None
        terminate(process, timeout)
        self._close()
        return process.returncode

    def kill(self) -> None:
        """SIGKILL the executive, as a crash would; its components end by themselves."""
        process = self._process
        if process is not None:
            process.kill()
            process.wait()
        self._close()

    def login(self) -> Login | None:
        """The operator's login to this robot's bus (its credentials are in the folder)."""
        return security.find_login(self.robot.name, security.OPERATOR, [self.folder])

    @property
    def credentials(self) -> Path:
        """The robot's bus credentials, as ``dura`` commands run elsewhere need them
        (``DURA_BUS_CREDENTIALS``)."""
        return security.credentials_file(self.folder, self.robot.name)

    def environment(self) -> dict[str, str]:
        """The environment for a ``dura`` command run against this robot from any folder."""
        return {**os.environ, security.ENV_CREDENTIALS: str(self.credentials)}

    def _close(self) -> None:
        if self._bus is not None:
            self._bus.close()
        self._bus, self._process = None, None
        self._running.clear()

    @property
    def running(self) -> bool:
        return self._process is not None and self._process.poll() is None

    def log_tail(self, lines: int = 20) -> str:
        with contextlib.suppress(OSError):
            return "\n".join(self.output.read_text(errors="replace").splitlines()[-lines:])
        return ""

    # --- the bus API ---------------------------------------------------------------------

    @property
    def bus(self) -> Bus:
        if self._bus is None:
            raise DuraError(f"the executive of '{self.robot.name}' does not run")
        return self._bus

    def request(
        self, verb: str, payload: Mapping[str, Any] | None = None, timeout: float = 30.0
    ) -> dict[str, Any]:
        """Ask the executive (``executive/api/<verb>``); raises BusError on an error reply."""
        return self.bus.request(api(verb), dict(payload or {}), timeout=timeout)

    def submit_goal(
        self,
        expression: str,
        *,
        priority: int = 0,
        deadline: float | None = None,
        keep: bool = False,
    ) -> int:
        """Submit a goal (``keep``: a maintenance goal); returns its id. Raises BusError if
        the executive refuses it."""
        request = planning.GoalAdd(expression, priority, deadline, keep=keep)
        return int(planning.GOAL_ADD.call(self.bus, request).goal["id"])

    def goal(self, goal_id: int) -> dict[str, Any]:
        return planning.GOAL_SHOW.call(self.bus, planning.GoalId(goal_id)).goal

    def goals(self) -> list[dict[str, Any]]:
        return planning.GOAL_LIST.call(self.bus).goals

    def wait_for(
        self, goal_id: int, state: str | GoalState = GoalState.ACHIEVED, timeout: float = 60.0
    ) -> dict[str, Any]:
        """Wait until a goal is in ``state``; returns the goal.

        Raises:
            GoalEnded: the goal ended in another state, or ``timeout`` passed (the
                message has the goal's state and reason and the latest events).
        """
        wanted = GoalState(state)
        deadline = time.monotonic() + timeout
        while True:
            goal = self.goal(goal_id)
            now = GoalState(goal["state"])
            if now is wanted:
                return goal
            ended = not now.is_open and now is not GoalState.UNREACHABLE
            if ended or time.monotonic() > deadline:
                why = f": {goal['reason']}" if goal["reason"] else ""
                raise GoalEnded(
                    f"goal {goal_id} {goal['expression']} is {now.value}{why}, not "
                    f"{wanted.value}; the latest events:\n{self._recent()}"
                )
            time.sleep(0.05)

    def wait_for_component(
        self, name: str, state: str = "ready", timeout: float = 60.0
    ) -> dict[str, Any]:
        """Wait until the launcher reports a component in ``state`` (``ready``: started
        and configured, so it takes faults and goals); returns its state payload.

        Raises:
            WaitTimedOut: not within ``timeout`` seconds (with its last state and the
                latest events).
            DuraError: the robot has no such component.
        """
        if name not in self.robot.components:
            raise DuraError(f"robot '{self.robot.name}' has no component '{name}'")
        deadline = time.monotonic() + timeout
        while True:
            found = next((c for c in self.components() if c.get("component") == name), {})
            if found.get("state") == state:
                return found
            if time.monotonic() > deadline:
                raise WaitTimedOut(
                    f"component {name} is {found.get('state', 'unknown')}, not {state}, "
                    f"after {timeout:g} s; the latest events:\n{self._recent()}"
                )
            time.sleep(0.05)

    def wait_for_event(
        self, kind: str, subject: str = "", *, after: int = 0, timeout: float = 60.0
    ) -> dict[str, Any]:
        """Wait for the first event of ``kind`` whose subject contains ``subject``,
        logged after the event numbered ``after``; returns it.

        Raises:
            WaitTimedOut: none within ``timeout`` seconds (with the latest events).
        """
        deadline = time.monotonic() + timeout
        while True:
            query = planning.EventQuery(after=after, limit=10_000, kind=kind, oldest=True)
            for event in planning.EVENTS.call(self.bus, query).events:
                if subject in event["subject"]:
                    return event
            if time.monotonic() > deadline:
                raise WaitTimedOut(
                    f"no {kind} event{f' about {subject}' if subject else ''} within "
                    f"{timeout:g} s; the latest events:\n{self._recent()}"
                )
            time.sleep(0.05)

    def _recent(self, count: int = 15) -> str:
        return "\n".join(
            f"  {e['kind']} {e['subject']} {e['data']}" for e in self.events()[-count:]
        )

    def components(self) -> list[dict[str, Any]]:
        """Every component's state payload (``component``, ``state``, ``pid``, ...)."""
        return COMPONENT_LIST.call(self.bus).components

    def cancel_goal(self, goal_id: int) -> None:
        planning.GOAL_CANCEL.call(self.bus, planning.GoalId(goal_id))

    def inject_fault(
        self, name: str, mode: str, *, timeout: float = INJECT_TIMEOUT, **options: Any
    ) -> None:
        """Make a component misbehave (see :mod:`executive.sdk.fault_injection`) as soon
        as it runs: waits at most ``timeout`` seconds for it to be ready.

        Raises:
            DuraError: it did not run in time, or the executive refused the fault (an
                unknown mode or option: the reason).
        """
        deadline = time.monotonic() + timeout
        while (state := self.component_state(name)) != Lifecycle.READY.value:
            if time.monotonic() > deadline:
                raise DuraError(
                    f"cannot inject {mode!r} into '{name}': it is {state}, not running "
                    f"(waited {timeout:g} s)"
                )
            time.sleep(0.05)
        try:
            COMPONENT_INJECT.call(self.bus, Injection(name, mode, dict(options)))
        except BusError as e:
            raise DuraError(f"cannot inject {mode!r} into '{name}': {e}") from None

    def component_state(self, name: str) -> str:
        """A component's state (``ready``, ``stopped``, ...).

        Raises:
            DuraError: the robot has no such component.
        """
        for listed in self.components():
            if listed["component"] == name:
                return str(listed["state"])
        raise DuraError(f"robot '{self.robot.name}' has no component '{name}'")

    def events(self, kind: str | None = None, limit: int = 10_000) -> list[dict[str, Any]]:
        """The event log, oldest first (only events of ``kind`` if given)."""
        return planning.EVENTS.call(self.bus, planning.EventQuery(limit=limit, kind=kind)).events

    def facts(self, pattern: str = "") -> list[str]:
        """The true facts and values as text, e.g. ``(robot_at dock)``."""
        reply = planning.STATE_GET.call(self.bus, planning.StateQuery(pattern))
        return [f["text"] for f in reply.facts]

    def set_fact(self, fact: str) -> None:
        """Make a fact true (or set a value: ``(= (battery) 80)``), as ``dura state set``."""
        planning.STATE_SET.call(self.bus, planning.FactChange(fact))

    def unset_fact(self, fact: str) -> None:
        """Make a fact false, as ``dura state unset``."""
        planning.STATE_UNSET.call(self.bus, planning.FactChange(fact))

    def status(self) -> dict[str, Any]:
        return planning.STATUS.call(self.bus).to_payload()


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
