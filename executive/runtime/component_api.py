"""The launcher's bus API for the command line: list, start, stop and logs of components,
and fault injection.

The verbs are declared in :mod:`executive.bus.api.components`; requests are checked
there. Achievements (``component/achieve``) are served by the launcher itself
(:mod:`executive.runtime.behavior_goals`): behaviors store them while the launcher runs,
with or without this API. Starts and stops by hand go to whoever supervises the
components (the task executor, in the executive), else straight to the launcher.
"""

from __future__ import annotations

import contextlib
import dataclasses
import socket
from typing import Any, Protocol

from executive.bus.api.components import (
    COMPONENT_INJECT,
    COMPONENT_LIST,
    COMPONENT_LOGS,
    COMPONENT_START,
    COMPONENT_STOP,
    ComponentName,
    ComponentsReply,
    Injection,
    LogQuery,
    LogReply,
)
from executive.bus.payloads import ComponentState
from executive.bus.reports import ComponentEntry
from executive.bus.service import Context, Service
from executive.bus.verb import Empty
from executive.runtime.launcher import Launcher
from executive.sdk.fault_injection import Fault


class ByHand(Protocol):
    """Who starts and stops components for a user, and supervises them afterwards."""

    def start_by_hand(self, name: str) -> ComponentState: ...

    def stop_by_hand(self, name: str) -> ComponentState: ...


class _LauncherByHand:
    def __init__(self, launcher: Launcher) -> None:
        self.launcher = launcher

    def start_by_hand(self, name: str) -> ComponentState:
        return self.launcher.start(name)

    def stop_by_hand(self, name: str) -> ComponentState:
        return self.launcher.stop(name)


class ComponentApi(Service):
    """Serves list, start, stop, logs and fault injection of the robot's components (the
    task executor
    serves restart, fault and reset: they count as faults).

    Args:
        by_hand: starts and stops for users (default: the launcher, unsupervised).
    """

    name = "component-api"

    def __init__(self, context: Context, launcher: Launcher, by_hand: ByHand | None = None) -> None:
        super().__init__(context)
        self.launcher = launcher
        self.by_hand = by_hand or _LauncherByHand(launcher)
        self._declared: list[Any] = []

    def on_activate(self) -> None:
        bus = self.context.bus
        self._declared = [
            COMPONENT_LIST.serve(bus, self._list),
            COMPONENT_LOGS.serve(bus, self._logs),
            COMPONENT_START.serve(bus, self._start),
            COMPONENT_STOP.serve(bus, self._stop),
            COMPONENT_INJECT.serve(bus, self._inject),
        ]

    def on_deactivate(self) -> None:
        for entity in self._declared:
            with contextlib.suppress(Exception):
                entity.undeclare()
        self._declared = []

    def _list(self, request: Empty) -> ComponentsReply:
        launcher = self.launcher
        return ComponentsReply(
            [
                dataclasses.replace(listed(launcher, state), log=launcher.log_path(state.component))
                for state in launcher.states()
            ]
        )

    def _start(self, request: ComponentName) -> ComponentState:
        return self.by_hand.start_by_hand(request.name)

    def _stop(self, request: ComponentName) -> ComponentState:
        return self.by_hand.stop_by_hand(request.name)

    def _inject(self, request: Injection) -> ComponentState:
        """Check the fault here (its mode and options), then send it to the component."""
        fault = Fault.parse({"mode": request.mode, **request.options})
        self.launcher.inject_fault(request.name, fault.to_spec())
        return self.launcher.state(request.name)

    def _logs(self, request: LogQuery) -> LogReply:
        name = request.name
        return LogReply(name, self.launcher.log_path(name), self.launcher.logs(name, request.lines))


def listed(launcher: Launcher, state: ComponentState) -> ComponentEntry:
    """A component as lists show it: its kind, host and state, and a pid only while it
    runs (a stopped component's last pid may belong to another process by now). The
    host is its agent's name, or the executive's computer's (``hostname``)."""
    host = launcher.host(state.component)
    return ComponentEntry(
        kind=launcher.kind(state.component).value,
        host=host if host is not None else _hostname(),
        component=state.component,
        state=state.state,
        pid=state.pid if state.state.is_alive else None,
        exit_code=state.exit_code,
        signal=state.signal,
        reason=state.reason,
        stamp=state.stamp,
        output=state.output,
    )


def _hostname() -> str:
    return socket.gethostname()
