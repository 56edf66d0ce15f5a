"""Mark a component faulty through the task executor."""

from __future__ import annotations

from monitoring.repair.actions.restart import RestartAction


class FaultAction(RestartAction):
    """``executive/api/component/fault`` with ``{name, reason}``; configured as restart."""

    type = "fault"
    verb = "component/fault"

    def describe(self) -> str:
        return f"mark {self.component} faulty"
