"""Repair actions: what a rule does when it fires (thesis 5.3, 6.3.4).

An action is a frozen dataclass whose fields are its keys in the rule's YAML entry (the
typed reader reads them, :mod:`knowledge.typed_reader`); the rule engine runs it on a
worker thread, and it bounds its own waiting by ``timeout`` seconds. Built-in actions
live in ``monitoring/repair/actions/``; others register in the entry-point group
``dura.actions`` (name = the rule ``type``, value = an :class:`Action` subclass, a
frozen keyword-only dataclass).
"""

from __future__ import annotations

import logging
import string
from abc import ABC, abstractmethod
from dataclasses import dataclass, field
from importlib import metadata
from pathlib import Path
from typing import Annotated, Any, ClassVar

from executive.bus.session import Bus
from knowledge.conventions import AtLeast
from knowledge.errors import ConfigError

log = logging.getLogger("dura.repair")

DEFAULT_TIMEOUT = 10.0


@dataclass(frozen=True)
class Firing:
    """Why a rule fired: what its texts may mention as ``$rule``, ``$faulty``, ``$failed``."""

    rule: str
    faulty: tuple[str, ...] = ()  # every possibly faulty component of the newest diagnosis
    failed: tuple[str, ...] = ()  # the failed observations, as 'type[resources]'
    stamp: float = 0.0

    def fill(self, text: str) -> str:
        """A text with ``$rule``, ``$faulty`` and ``$failed`` replaced."""
        return string.Template(text).safe_substitute(
            rule=self.rule, faulty=", ".join(self.faulty), failed="; ".join(self.failed)
        )


@dataclass(frozen=True)
class ActionContext:
    """What actions may use: the bus (for the executive's API) and the robot's folder."""

    bus: Bus | None = None
    folder: Path = field(default_factory=Path.cwd)


@dataclass(frozen=True, kw_only=True)
class Action(ABC):
    """One kind of repair action: its fields are the keys of a rule that configure it."""

    type: ClassVar[str]
    timeout: Annotated[float, AtLeast(0.001)] = DEFAULT_TIMEOUT  # seconds it may take

    def run(self, context: ActionContext, firing: Firing) -> None:
        """Carry the action out; raises :class:`DuraError` (or OSError) if it failed."""
        self._run(context, firing)

    @abstractmethod
    def _run(self, context: ActionContext, firing: Firing) -> None: ...

    def describe(self) -> str:
        """What the action does, in a few words."""
        return self.type

    @staticmethod
    def _bus(context: ActionContext) -> Bus:
        if context.bus is None:
            raise ConfigError("this action needs the bus, and there is none")
        return context.bus


def _builtins() -> dict[str, type[Action]]:
    from monitoring.repair.actions import (  # here: each of them imports this module
        command,
        fault,
        goal,
        logentry,
        mail,
        parameter,
        process,
        restart,
    )

    kinds: list[type[Action]] = [
        restart.RestartAction,
        fault.FaultAction,
        logentry.LogAction,
        mail.MailAction,
        process.ProcessAction,
        command.CommandAction,
        parameter.ParameterAction,
        goal.GoalAction,
    ]
    return {k.type: k for k in kinds}


# The names the tug reporter used for the same actions.
ALIASES = {"email": "mail", "logfile": "log", "print": "log", "paramter": "parameter"}


def action_types() -> dict[str, type[Action]]:
    """Every action type: the built-ins, then plugins; a broken plugin is a warning."""
    kinds = _builtins()
    for entry in metadata.entry_points(group="dura.actions"):
        try:
            loaded: Any = entry.load()
        except Exception as e:  # a plugin may fail in any way; dura goes on without it
            log.warning("action plugin '%s' failed to load: %s", entry.name, e)
            continue
        if isinstance(loaded, type) and issubclass(loaded, Action):
            kinds.setdefault(entry.name, loaded)
        else:
            log.warning("action plugin '%s' is not an Action class", entry.name)
    return kinds
