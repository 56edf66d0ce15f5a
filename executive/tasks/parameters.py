"""Component parameters at run time: checked against the robot description, stored in
the knowledge base, and handed to the running component.

A parameter the description gives a value keeps that value's type: a float takes any
number (a whole one becomes a float), an int a whole number, a bool only true or
false, a string only a string, a list a list, a mapping a mapping; a parameter the
description does not name takes any value. A running component gets a changed
parameter through its ``on_reconfigure`` hook; one that cannot take it so (no hook, or
the hook failed) is restarted warm with the new parameters, the tasks on it held as
during a repair. A component that does not run takes it at its next start.
"""

from __future__ import annotations

import math
import re
from collections.abc import Callable, Mapping
from typing import Any

from executive.bus.api.parameters import ParameterReply, ParametersReply
from executive.bus.payloads import ComponentState
from executive.bus.states import Lifecycle
from executive.runtime.launcher import Launcher
from knowledge.description import ComponentSpec, RobotDescription
from knowledge.errors import ComponentError, ConfigError, excerpt
from knowledge.knowledge_base import KnowledgeBase

DESCRIPTION, KNOWLEDGE_BASE = "description", "knowledge base"
# a key set at run time, beyond those of the description: stored, listed and shown
PARAMETER_KEY = re.compile(r"[A-Za-z_][A-Za-z0-9_.-]{0,63}")
PARAMETER_KEY_RULE = "must be a letter or '_', then up to 63 letters, digits, '_', '-' or '.'"
RECONFIGURED, RESTARTED, STORED = "reconfigured", "restarted", "stored"

_KINDS: tuple[tuple[type, str], ...] = (
    (bool, "true or false"),
    (int, "a whole number"),
    (float, "a number"),
    (str, "a string"),
    (list, "a list"),
    (dict, "a mapping"),
)


def checked(component: ComponentSpec, key: str, value: Any) -> Any:
    """The value to store for ``component``'s parameter ``key``.

    Raises:
        ConfigError: the key breaks the name rule (one the description does not give),
            or the value is not of the type the description gives the parameter.
    """
    if key not in component.params and not PARAMETER_KEY.fullmatch(key):
        raise ConfigError(f"parameter key '{excerpt(key, 64)}' {PARAMETER_KEY_RULE}")
    described = component.params.get(key)
    found = next(((k, w) for k, w in _KINDS if isinstance(described, k)), None)
    if found is None:  # not in the description (or null there): any value
        return value
    kind, words = found
    number = isinstance(value, int | float) and not isinstance(value, bool)
    if kind is float and number and math.isfinite(value):
        return float(value)
    if kind is int and number and float(value).is_integer():
        return int(value)
    if kind not in (int, float) and isinstance(value, kind):
        return value
    raise ConfigError(
        f"parameter '{key}' of '{component.name}' must be {words} (the description gives "
        f"{excerpt(repr(described))}), not {excerpt(repr(value))}"
    )


class RuntimeParameters:
    """Sets, gets and lists the parameters of a robot's components.

    Args:
        restart: restarts a running component warm (its tasks held meanwhile) with the
            reason; on the task executor's worker.
    """

    def __init__(
        self,
        robot: RobotDescription,
        kb: KnowledgeBase,
        launcher: Launcher,
        *,
        restart: Callable[[str, str], ComponentState],
    ) -> None:
        self.robot = robot
        self.kb = kb
        self.launcher = launcher
        self._restart = restart

    def set(self, name: str, key: str, value: Any) -> ParameterReply:
        """Check, store and apply a new value (on the task executor's worker).

        Raises:
            ComponentError: no such component.
            ConfigError: a value of the wrong type.
        """
        value = checked(self._spec(name), key, value)
        applied, reason = STORED, ""
        if self.launcher.state(name).state in (Lifecycle.READY, Lifecycle.PAUSED):
            try:
                self.launcher.reconfigure(name, {key: value})
                applied = RECONFIGURED
            except ComponentError as e:
                applied, reason = RESTARTED, str(e)
        self.kb.set_parameter(name, key, value)
        if applied == RESTARTED:
            state = self._restart(name, f"new parameter {key}={value!r}")
            if state.state is not Lifecycle.READY:
                reason = f"{reason}; the restart failed: {state.reason}"
        return ParameterReply(name, key, value, KNOWLEDGE_BASE, applied, reason)

    def get(self, name: str, key: str) -> ParameterReply:
        """A parameter's value and source.

        Raises:
            ComponentError: no such component, or it has no such parameter.
        """
        values, sources = self._effective(name)
        if key not in values:
            known = ", ".join(sorted(values)) or "none"
            raise ComponentError(f"'{name}' has no parameter '{key}' (its parameters: {known})")
        return ParameterReply(name, key, values[key], sources[key])

    def list(self, name: str) -> ParametersReply:
        values, sources = self._effective(name)
        return ParametersReply(name, values, sources)

    def _effective(self, name: str) -> tuple[dict[str, Any], dict[str, str]]:
        described: Mapping[str, Any] = self._spec(name).params
        stored = self.kb.parameters(name)
        values = {**described, **stored}
        sources = {k: KNOWLEDGE_BASE if k in stored else DESCRIPTION for k in values}
        return dict(sorted(values.items())), dict(sorted(sources.items()))

    def _spec(self, name: str) -> ComponentSpec:
        self.launcher.kind(name)  # refuses an unknown name
        return self.robot.components[name]
