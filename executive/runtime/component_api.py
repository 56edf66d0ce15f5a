"""The launcher's bus API for the command line: list, start, stop and logs of components.

The verbs are declared in :mod:`executive.bus.api.components`; requests are checked
there. Achievements (``component/achieve``) are served by the launcher itself
(:mod:`executive.runtime.behavior_goals`): behaviors store them while the launcher runs,
with or without this API.
"""

from __future__ import annotations

import contextlib
from typing import Any

from executive.bus.api.components import (
    COMPONENT_LIST,
    COMPONENT_LOGS,
    COMPONENT_START,
    COMPONENT_STOP,
    ComponentName,
    ComponentsReply,
    LogQuery,
    LogReply,
)
from executive.bus.payloads import ComponentState
from executive.bus.service import Context, Service
from executive.bus.verb import Empty
from executive.runtime.launcher import Launcher


class ComponentApi(Service):
    """Serves list, start, stop and logs of the robot's components (the task executor
    serves restart, fault and reset: they count as faults)."""

    name = "component-api"

    def __init__(self, context: Context, launcher: Launcher) -> None:
        super().__init__(context)
        self.launcher = launcher
        self._declared: list[Any] = []

    def start(self) -> None:
        bus = self.context.bus
        self._declared = [
            COMPONENT_LIST.serve(bus, self._list),
            COMPONENT_LOGS.serve(bus, self._logs),
            COMPONENT_START.serve(bus, self._start),
            COMPONENT_STOP.serve(bus, self._stop),
        ]

    def stop(self) -> None:
        for entity in self._declared:
            with contextlib.suppress(Exception):
                entity.undeclare()
        self._declared = []

    def _list(self, request: Empty) -> ComponentsReply:
        launcher = self.launcher
        return ComponentsReply(
            [
                {
                    "kind": launcher.kind(state.component).value,
                    "log": str(launcher.log_path(state.component)),
                    **state.to_payload(),
                }
                for state in launcher.states()
            ]
        )

    def _start(self, request: ComponentName) -> ComponentState:
        return self.launcher.start(request.name)

    def _stop(self, request: ComponentName) -> ComponentState:
        return self.launcher.stop(request.name)

    def _logs(self, request: LogQuery) -> LogReply:
        name = request.name
        return LogReply(
            name, str(self.launcher.log_path(name)), self.launcher.logs(name, request.lines)
        )
