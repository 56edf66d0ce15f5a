"""The launcher's bus API for the command line: ``executive/api/component/*``.

Payloads are documented in :mod:`executive.bus.keys` and :mod:`executive.bus.payloads`.
"""

from __future__ import annotations

import contextlib
from typing import Any

from executive.bus.keys import api
from executive.bus.service import Context, Service
from executive.runtime.launcher import Launcher
from knowledge.errors import ComponentError

MAX_LOG_LINES = 10_000


def _name(request: dict[str, Any]) -> str:
    name = request.get("name")
    if not isinstance(name, str) or not name:
        raise ComponentError(f"the request needs a component 'name', not {name!r}")
    return name


class ComponentApi(Service):
    """Serves list, start, stop and logs of the robot's components (the task executor
    serves restart, fault and reset: they count as faults)."""

    name = "component-api"

    def __init__(self, context: Context, launcher: Launcher) -> None:
        super().__init__(context)
        self.launcher = launcher
        self._declared: list[Any] = []

    def start(self) -> None:
        bus, launcher = self.context.bus, self.launcher
        self._declared = [
            bus.serve(api("component/list"), self._list),
            bus.serve(api("component/logs"), self._logs),
            bus.serve(
                api("component/start"),
                lambda r: launcher.start(_name(r)).to_payload(),
                threaded=True,
            ),
            bus.serve(
                api("component/stop"),
                lambda r: launcher.stop(_name(r)).to_payload(),
                threaded=True,
            ),
        ]

    def stop(self) -> None:
        for entity in self._declared:
            with contextlib.suppress(Exception):
                entity.undeclare()
        self._declared = []

    def _list(self, request: dict[str, Any]) -> dict[str, Any]:
        launcher = self.launcher
        return {
            "components": [
                {
                    "kind": launcher.kind(state.component).value,
                    "log": str(launcher.log_path(state.component)),
                    **state.to_payload(),
                }
                for state in launcher.states()
            ]
        }

    def _logs(self, request: dict[str, Any]) -> dict[str, Any]:
        name = _name(request)
        lines = request.get("lines", 50)
        if not isinstance(lines, int) or isinstance(lines, bool) or not 0 <= lines <= MAX_LOG_LINES:
            raise ComponentError(f"'lines' must be a whole number from 0 to {MAX_LOG_LINES}")
        return {
            "name": name,
            "path": str(self.launcher.log_path(name)),
            "lines": self.launcher.logs(name, lines),
        }
