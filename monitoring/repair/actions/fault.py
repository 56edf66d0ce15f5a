"""Mark a component faulty through the task executor."""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

from executive.bus.api import tasks as api
from executive.bus.verb import Verb
from monitoring.repair.actions.restart import RestartAction


@dataclass(frozen=True, kw_only=True)
class FaultAction(RestartAction):
    """``component/fault`` of the task executor with ``{name, reason}``; configured as
    restart."""

    type = "fault"
    verb: ClassVar[Verb[api.ComponentFault, api.FaultReply]] = api.COMPONENT_FAULT

    def describe(self) -> str:
        return f"mark {self.component} faulty"
