"""Send a command (any verb) to the executive."""

from __future__ import annotations

from knowledge.yamlsource import Section
from monitoring.repair.action import Action, ActionContext, Firing
from monitoring.repair.actions.executive import ExecutiveAction


class CommandAction(ExecutiveAction):
    """``executive/api/<verb>`` with ``payload`` (a mapping)."""

    type = "command"

    def describe(self) -> str:
        return f"command executive/api/{self.verb}"

    def __init__(self, verb: str, payload: dict[str, object], timeout: float) -> None:
        super().__init__(timeout)
        self.verb = verb
        self.payload = payload

    @classmethod
    def configure(cls, entry: Section, timeout: float) -> Action:
        verb = cls._require(entry, "verb").strip("/")
        return cls(verb, entry.plain("payload"), timeout)

    def _run(self, context: ActionContext, firing: Firing) -> None:
        payload = {k: firing.fill(v) if isinstance(v, str) else v for k, v in self.payload.items()}
        self.request(context, self.verb, payload)
