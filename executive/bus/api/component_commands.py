"""The lifecycle commands every component process serves on ``component/<name>/cmd``:
one payload type per verb (the launcher sends them, the SDK's framework answers)."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import field
from typing import Any, ClassVar

from executive.bus.api.free_form import GoalFields, Params, Value
from executive.bus.schema import Payload, PayloadError, Text
from executive.bus.states import Command, ComponentPhase
from knowledge.record_class import record


class ComponentCommand(Payload):
    """A lifecycle command, ``{"cmd": verb, **fields}``: one type per verb (below).

    The component answers with a :class:`CommandReply`, or refuses with the reason.
    The key is the component's own, so these are not :class:`Verb` constants.
    """

    verb: ClassVar[Command]

    def to_request(self) -> dict[str, Any]:
        return {"cmd": self.verb.value, **self.to_payload()}

    @staticmethod
    def from_request(request: Mapping[str, Any]) -> ComponentCommand:
        """The command a request names, its fields checked by the verb's type.

        Raises:
            PayloadError: an unknown verb, or a field that does not fit.
        """
        verb = request.get("cmd")
        command = next((c for c in COMMANDS if c.verb.value == verb), None)
        if command is None:
            verbs = ", ".join(c.value for c in Command)
            raise PayloadError(f"unknown command {verb!r} (choose from {verbs})")
        return command.from_payload(request)


@record
class Configure(ComponentCommand):
    """Parameters, and the achievements kept for a warm start."""

    verb = Command.CONFIGURE
    params: Params = field(default_factory=dict)
    achievements: Params = field(default_factory=dict)


@record
class Start(ComponentCommand):
    """Start running (after configure)."""

    verb = Command.START


@record
class Pause(ComponentCommand):
    """Pause until resumed."""

    verb = Command.PAUSE


@record
class Resume(ComponentCommand):
    """Resume after a pause."""

    verb = Command.RESUME


@record
class Reconfigure(ComponentCommand):
    """Changed parameters only."""

    verb = Command.RECONFIGURE
    params: Params = field(default_factory=dict)


@record
class Stop(ComponentCommand):
    """Stop and exit."""

    verb = Command.STOP


@record
class TakeGoal(ComponentCommand):
    """A behavior's goal: the reply comes at once, the result later on
    ``component/<name>/result``."""

    verb = Command.GOAL
    goal_id: Text
    goal: GoalFields = field(default_factory=dict)


@record
class CancelGoal(ComponentCommand):
    """Cancel the goal the behavior is carrying out."""

    verb = Command.CANCEL
    goal_id: Text


@record
class InjectFault(ComponentCommand):
    """``"crash"`` or ``{"mode": "crash", ...}`` (see :mod:`executive.sdk.fault_injection`)."""

    verb = Command.INJECT_FAULT
    fault: str | dict[str, Value]


COMMANDS: tuple[type[ComponentCommand], ...] = (
    Configure,
    Start,
    Pause,
    Resume,
    Reconfigure,
    Stop,
    TakeGoal,
    CancelGoal,
    InjectFault,
)


@record
class CommandReply(Payload):
    """Where the component is after the command."""

    phase: ComponentPhase
