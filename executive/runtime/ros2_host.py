"""The host of a ROS 2 program: dura's lifecycle commands carried to a ROS 2 node.

The launcher runs ``python -m executive.runtime.ros2_host -- PROGRAM ...`` for a
component with a ``ros2:`` key (:mod:`executive.runtime.ros2_launch`). The host is an
SDK component, so the executive starts, stops, pauses and supervises it like any
other; the program runs as its child in the host's process group, and when the
program ends on its own the host ends the same way (a crash is a crash). The host
joins the robot's ROS 2 domain with a participant of its own.

- configure: start the program, then wait until its node is in the ROS 2 graph (a
  plain node), serves its lifecycle services (a managed node, which is then
  configured), or until the action or service of a behavior has a server.
- start / resume: activate a managed node; resume a paused program (SIGCONT).
- pause: deactivate a managed node, or pause the program (SIGSTOP); a behavior's
  running action goal is cancelled (and sent again on resume).
- stop: deactivate and clean up a managed node, then end the program (SIGTERM, then
  SIGKILL).

A transition a managed node refuses fails the command with the reason, so a failed
configure or activate is a failed start. A managed node that leaves the state dura
put it in on its own (an error, a shutdown) ends the host with exit code 1: a fault.
"""

from __future__ import annotations

import atexit
import contextlib
import logging
import os
import signal
import sys
import threading
import time
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

from executive.bus import keys
from executive.ros2.action import ActionClient
from executive.ros2.discovery import Discovery
from executive.ros2.lifecycle_node import LifecycleClient, TransitionOutcome
from executive.ros2.participant import Participant
from executive.ros2.service_client import ServiceClient
from executive.ros2.types import TypeLibrary
from executive.runtime.ros2_goals import ActionGoals, ServiceGoals
from executive.runtime.ros2_launch import ENV_CONFIG, HostConfig
from executive.runtime.translators.process import ProcessTranslator
from executive.sdk import Behavior, Functionality
from knowledge.description import Kind
from knowledge.errors import BusError, ComponentError, DuraError
from knowledge.ros2_messages import message_store

ANSWER = 5.0  # seconds a managed node gets to answer one service call
LOOK = 0.05  # seconds between two looks at the graph while waiting for the node
USAGE = "usage: python -m executive.runtime.ros2_host -- [PROGRAM ARG ...]"
PRIMARY = ("unconfigured", "inactive", "active", "finalized")


class Ros2Host:
    """Carries lifecycle commands (and a behavior's goals) to one ROS 2 program.

    Args:
        name: the component's name (the host's own node is ``dura_<name>``).
        config: the component's ROS 2 side, from the launcher.
        argv: the program (empty: a behavior that only calls an action or a service).
        log: the host component's logger.
        on_exit: told the program's return code when it ends on its own, or 1 when a
            managed node left its state on its own.
    """

    def __init__(
        self,
        name: str,
        config: HostConfig,
        argv: Sequence[str],
        log: logging.Logger,
        on_exit: Callable[[int], None],
    ) -> None:
        self.config = config
        self.log = log
        self.on_exit = on_exit
        self.program = ProcessTranslator(argv, log, on_exit) if argv else None
        self.library = TypeLibrary(
            message_store(config.distribution, [Path(p) for p in config.messages]),
            config.distribution,
        )
        self.participant = Participant(config.domain_id, name=f"dura_{name}")
        self.lifecycle: LifecycleClient | None = None
        self.goals: ActionGoals | ServiceGoals | None = None
        self._closers: list[Callable[[], None]] = []
        self._wanted = "unconfigured"  # the state dura put a managed node in
        self._launched = False
        self._changing = threading.Lock()  # held while dura drives a transition
        try:
            self.discovery = Discovery(self.participant, self.library, node=f"dura_{name}")
            self._closers.append(self.discovery.close)
            self._open_call()
            if config.lifecycle and config.node is not None:
                self.lifecycle = LifecycleClient(
                    self.participant, self.library, config.node,
                    discovery=self.discovery, on_transition=self._heard_transition,
                )  # fmt: skip
                self._closers.append(self.lifecycle.close)
        except BaseException:
            self.close()
            raise

    def _open_call(self) -> None:
        call = self.config.call
        if call is None:
            return
        name, kind = call["name"], call["type"]
        if call["kind"] == "action":
            action = ActionClient(
                self.participant, self.library, name, kind, discovery=self.discovery
            )
            self._closers.append(action.close)
            self.goals = ActionGoals(action, self.library, self.log)
        else:
            service = ServiceClient(
                self.participant, self.library, name, kind, discovery=self.discovery
            )
            self._closers.append(service.close)
            self.goals = ServiceGoals(service, self.library)

    # --- dura's commands ------------------------------------------------------------

    def configure(self, params: dict[str, Any]) -> None:
        """Start the program and wait until its node (or its server) is there.

        Raises:
            ComponentError: the program cannot start, its node did not come, or a
                managed node refused to configure.
        """
        deadline = time.monotonic() + max(1.0, self.config.startup_timeout - 1.0)
        if self.program is not None and not self._launched:  # configured twice: once
            self._launched = True
            try:
                self.program.start(params)
            except OSError as e:
                raise ComponentError(
                    f"cannot run {self.program.argv[0]!r}: {e.strerror or e}"
                ) from e
        node, call = self.config.node, self.config.call
        if self.lifecycle is not None:
            self._await(lambda: self.lifecycle is not None and self.lifecycle.wait(LOOK),
                        deadline, f"managed node {node} serves no lifecycle services")  # fmt: skip
            self._drive("configure")
        elif node is not None:
            self._await(lambda: node in self.discovery.nodes(), deadline,
                        f"node {node} is not in the ROS 2 graph")  # fmt: skip
        if call is not None:
            limit = time.monotonic() + float(call["wait"])
            client = self.goals.client if self.goals is not None else None
            self._await(lambda: client is not None and client.ready(), min(deadline, limit),
                        f"ROS 2 {call['kind']} {call['name']} has no server")  # fmt: skip

    def _await(self, ready: Callable[[], bool], deadline: float, failure: str) -> None:
        started = time.monotonic()
        while not ready():
            if self.program is not None and self.program.exited():
                raise ComponentError(f"{failure}: the program ended")
            if time.monotonic() >= deadline:
                raise ComponentError(f"{failure} after {time.monotonic() - started:.1f} s")
            time.sleep(LOOK)

    def start(self) -> None:
        self._drive("start")

    def pause(self) -> None:
        if self.goals is not None and isinstance(self.goals, ActionGoals):
            self.goals.pause()
        if self.lifecycle is not None:
            self._drive("pause")
        elif self.program is not None:
            self.program.pause()

    def resume(self) -> None:
        if self.lifecycle is not None:
            self._drive("resume")
        elif self.program is not None:
            self.program.resume()
        if self.goals is not None and isinstance(self.goals, ActionGoals):
            self.goals.resume()

    def stop(self) -> None:
        """Clean up a managed node (best effort), then end the program."""
        if self.lifecycle is not None and (self.program is None or not self.program.exited()):
            try:
                self._drive("stop")
            except ComponentError as e:
                self.log.warning("%s", e)
        if self.program is not None:
            self.program.stop()

    def execute(self, goal: dict[str, Any], behavior: Behavior) -> dict[str, Any]:
        if self.goals is None:
            raise ComponentError("this ROS 2 behavior has no action or service for its goals")
        return self.goals.execute(goal, behavior)

    # --- managed nodes ----------------------------------------------------------------

    def _drive(self, command: str) -> None:
        """Carry out one of dura's commands on a managed node.

        Raises:
            ComponentError: a refused transition (with the state the node is in), or no answer.
        """
        if self.lifecycle is None:
            return
        node = self.config.node
        with self._changing:
            try:
                outcome = self.lifecycle.drive(command, timeout=ANSWER)
            except BusError as e:
                raise ComponentError(f"{command} of managed node {node}: {e}") from e
            if outcome is None:
                return
            self._wanted = outcome.state
        if not outcome.success:
            raise ComponentError(_refused(node, outcome))
        self.log.info("managed node %s is %s", node, outcome.state)

    def _heard_transition(self, transition: str, start: str, goal: str) -> None:
        """A managed node changed state (receive thread): was it dura's doing?"""
        if goal not in PRIMARY or goal == self._wanted:
            return
        threading.Thread(target=self._check_state, daemon=True, name="lifecycle-check").start()

    def _check_state(self) -> None:
        if self.lifecycle is None:
            return
        with self._changing:  # dura's own transitions end first
            wanted = self._wanted
            try:
                state = self.lifecycle.state(timeout=ANSWER)
            except BusError:
                return
        if state != wanted and state in PRIMARY:
            self.log.error("managed node %s went %s on its own (dura had it %s)",
                           self.config.node, state, wanted)  # fmt: skip
            self.on_exit(1)

    def close(self) -> None:
        """Close the ROS 2 side (the program is ended by :meth:`stop`)."""
        for close in reversed(self._closers):
            with contextlib.suppress(DuraError):
                close()
        self._closers.clear()
        self.participant.close()


def _refused(node: str | None, outcome: TransitionOutcome) -> str:
    return f"managed node {node} refused to {outcome.transition} (it is {outcome.state})"


class _Hosting:
    """What both host components do: forward the hooks, end as the program ended."""

    host: Ros2Host
    _framework: Any
    log: logging.Logger

    def _program_ended(self, returncode: int) -> None:
        """The program ended on its own (any thread): end this process the same way."""

        def end() -> None:
            self.log.warning("the ROS 2 program ended on its own (return code %d)", returncode)
            if returncode < 0:
                with contextlib.suppress(OSError, ValueError):  # SIGKILL has no handler
                    signal.signal(-returncode, signal.SIG_DFL)
                os.kill(os.getpid(), -returncode)
            self._framework.end(returncode)

        self._framework.post(end)


class Ros2Functionality(_Hosting, Functionality):
    """A functionality that is a ROS 2 program."""

    def __init__(self, name: str, bus: Any, config: HostConfig, argv: Sequence[str]) -> None:
        super().__init__(name, bus)
        self.host = Ros2Host(name, config, argv, self.log, self._program_ended)
        atexit.register(self.host.close)  # its participant leaves the graph at once

    def on_configure(self, params: dict[str, Any], achievements: dict[str, Any]) -> None:
        self.host.configure(params)

    def on_start(self) -> None:
        self.host.start()

    def on_pause(self) -> None:
        self.host.pause()

    def on_resume(self) -> None:
        self.host.resume()

    def on_stop(self) -> None:
        try:
            self.host.stop()
        finally:
            self.host.close()


class Ros2Behavior(_Hosting, Behavior):
    """A behavior whose goals go to a ROS 2 action or service (and maybe its program)."""

    def __init__(self, name: str, bus: Any, config: HostConfig, argv: Sequence[str]) -> None:
        super().__init__(name, bus)
        self.host = Ros2Host(name, config, argv, self.log, self._program_ended)
        atexit.register(self.host.close)  # its participant leaves the graph at once

    def on_configure(self, params: dict[str, Any], achievements: dict[str, Any]) -> None:
        self.host.configure(params)

    def on_start(self) -> None:
        self.host.start()

    def on_pause(self) -> None:
        self.host.pause()

    def on_resume(self) -> None:
        self.host.resume()

    def on_stop(self) -> None:
        try:
            self.host.stop()
        finally:
            self.host.close()

    def execute(self, goal: dict[str, Any]) -> dict[str, Any]:
        return self.host.execute(goal, self)


def main(argv: Sequence[str] | None = None) -> None:
    args = list(sys.argv[1:] if argv is None else argv)
    if args[:1] == ["--"]:
        del args[0]
    text = os.environ.get(ENV_CONFIG)
    if text is None:
        print(f"{USAGE}\n{ENV_CONFIG} is not set: the launcher starts hosts", file=sys.stderr)
        sys.exit(2)
    try:
        config = HostConfig.from_json(text)
    except DuraError as e:
        print(f"dura ros2 host: {e}", file=sys.stderr)
        sys.exit(2)
    behavior = os.environ.get(keys.ENV_KIND) == Kind.BEHAVIOR.value
    host = Ros2Behavior if behavior else Ros2Functionality
    sys.exit(host.run_process(config, args))


if __name__ == "__main__":
    main()
