"""The launcher: starts, watches and stops component processes (thesis 5.1.4, 6.1).

One facade over three concerns, each in a module of its own:

- :mod:`executive.runtime.processes` — the launcher thread that forks every component
  process, pumps its output into its log file and reaps it;
- :mod:`executive.runtime.component_lifecycle` — starting, stopping and commanding components,
  and their states (recorded by :mod:`executive.runtime.states`), on this computer or
  through the host agents of others (:mod:`executive.runtime.process_host`,
  :mod:`executive.runtime.remote_host`), alike;
- :mod:`executive.runtime.behavior_goals` — goals sent to behaviors, their results,
  return values and achievements in the KB.

The task executor and the executive use the :class:`Launcher` only.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

from executive.bus.payloads import ComponentState
from executive.bus.security import Credentials
from executive.bus.session import Bus
from executive.bus.states import Command
from executive.runtime.behavior_goals import BehaviorGoals, GoalHandle
from executive.runtime.component_lifecycle import LifecycleControl, local_endpoint
from executive.runtime.process_host import ProcessHost
from executive.runtime.remote_host import HostListener
from executive.runtime.states import Listener
from knowledge.description import Kind, RobotDescription
from knowledge.knowledge_base import KnowledgeBase

__all__ = ["GoalHandle", "HostListener", "Launcher", "Listener", "local_endpoint"]


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
        credentials: the robot's bus credentials (each component gets its own login).
        run_id: marks every process started, so that the next executive on the same
            knowledge base can end what this one leaves if it is killed
            (:mod:`executive.runtime.run_lock`).
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
        credentials: Credentials | None = None,
        run_id: str | None = None,
    ) -> None:
        self.robot = robot
        self.bus = bus
        self.kb = kb
        self.log_dir = log_dir
        self.grace = grace
        self._goals = BehaviorGoals(robot, bus, kb, command=self.command)
        self._control = LifecycleControl(
            robot,
            bus,
            kb,
            log_dir=log_dir,
            grace=grace,
            log_max_bytes=log_max_bytes,
            log_backups=log_backups,
            on_process_end=self._goals.process_ended,
            credentials=credentials,
            run_id=run_id,
        )
        self._running = False

    def open(self) -> Launcher:
        """Start the launcher's threads and bus subscriptions."""
        self._control.open()
        self._goals.open()
        self._running = True
        return self

    def close(self) -> None:
        """Stop every component (all at once), then the launcher's threads."""
        if not self._running:
            return
        self._control.stop_all()  # while goals still hear the results of their stop
        self._goals.close()
        self._control.close()
        self._running = False

    def __enter__(self) -> Launcher:
        return self.open()

    def __exit__(self, *exc: object) -> None:
        self.close()

    # --- queries ----------------------------------------------------------------------

    def kind(self, name: str) -> Kind:
        return self._control.spec(name).kind

    def state(self, name: str) -> ComponentState:
        return self._control.state(name)

    def states(self) -> list[ComponentState]:
        """The state of every component, in the robot description's order."""
        return self._control.states()

    def log_path(self, name: str) -> str:
        """Where a component's log is (``host:path`` on another computer)."""
        return self._host(name).log_path(name)

    def logs(self, name: str, lines: int = 50) -> list[str]:
        """The last lines of a component's log (from its host, for a remote one).

        Raises:
            ComponentError: no such component, or its host did not answer.
        """
        return self._host(name).logs(name, lines)

    def host(self, name: str) -> str | None:
        """The host a component is placed on (``None``: the executive's computer)."""
        return self._control.spec(name).host

    def hosts(self) -> dict[str, bool]:
        """Each host agent's host, and whether it is connected."""
        return self._control.hosts.connected()

    def unavailable(self) -> frozenset[str]:
        """The components placed on hosts whose agents are not there: none of them can
        start until the agent is back."""
        return self._control.hosts.unavailable()

    def add_host_listener(self, listener: HostListener) -> None:
        """Call ``listener(host, connected)`` when a host agent joins or is lost (after the
        components it ran have ended)."""
        self._control.hosts.add_listener(listener)

    def remove_host_listener(self, listener: HostListener) -> None:
        self._control.hosts.remove_listener(listener)

    def _host(self, name: str) -> ProcessHost:
        return self._control.hosts.of(self._control.spec(name))  # refuses an unknown name

    def add_listener(self, listener: Listener) -> None:
        """Call ``listener(state)`` at every state change of every component.

        Listeners run one after the other on one thread, in the order of the changes;
        they may call the launcher, but hold up the other listeners meanwhile.
        """
        self._control.records.add_listener(listener)

    def remove_listener(self, listener: Listener) -> None:
        self._control.records.remove_listener(listener)

    # --- lifecycle --------------------------------------------------------------------

    def start(self, name: str) -> ComponentState:
        """Start a component and wait until it is ready, or failed (a result).

        A component that is already running is left as it is. Waits at most the
        component's start-up timeout (then kills it: FAILED).
        """
        return self._control.start(name)

    def stop(self, name: str, reason: str = "stopped") -> ComponentState:
        """Stop a component and wait until its process is gone; returns its final state.

        The component gets a stop command, then SIGTERM, then SIGKILL (its whole
        process group), each after the grace period.
        """
        return self._control.stop(name, reason)

    def stop_soon(self, name: str, reason: str = "stopped") -> None:
        """Begin to stop a component and return at once; the stop goes on meanwhile, and
        a start of the component waits for it."""
        self._control.stop_soon(name, reason)

    def restart(self, name: str) -> ComponentState:
        """Stop (if running) and start again with the component's configuration."""
        self.stop(name, reason="restarting")
        return self.start(name)

    def command(self, name: str, verb: Command, **fields: Any) -> dict[str, Any]:
        """Send a lifecycle command to a running component and return its reply.

        Raises:
            ComponentError: the component is not running, refused or did not answer.
        """
        return self._control.command(name, verb, **fields)

    def pause(self, name: str) -> ComponentState:
        return self._control.pause(name)

    def resume(self, name: str) -> ComponentState:
        return self._control.resume(name)

    def reconfigure(self, name: str, params: Mapping[str, Any]) -> None:
        """Hand changed parameters to a running component."""
        self._control.reconfigure(name, params)

    def inject_fault(self, name: str, fault: str | Mapping[str, Any]) -> None:
        """Make a running component misbehave (see :mod:`executive.sdk.fault_injection`)."""
        self._control.inject_fault(name, fault)

    # --- behaviors --------------------------------------------------------------------

    def send_goal(
        self, name: str, goal: Mapping[str, Any], *, task_id: int | None = None
    ) -> GoalHandle:
        """Send a goal to a ready behavior; its result comes through the handle.

        Raises:
            ComponentError: not a behavior, not ready, or it refused the goal (busy).
        """
        return self._goals.send(self._control.spec(name), goal, task_id=task_id)
