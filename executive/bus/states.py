"""The states and verbs of components and their goals, as the bus carries them (by value)."""

from __future__ import annotations

import enum


class Lifecycle(enum.Enum):
    """Where a component process is in its life (published by the launcher)."""

    STARTING = "starting"  # process started, not yet ready
    READY = "ready"  # configured and running (functionalities) / waiting for a goal (behaviors)
    PAUSED = "paused"
    STOPPING = "stopping"
    STOPPED = "stopped"  # ended because it was asked to
    EXITED = "exited"  # ended on its own: finished, crashed or killed (see exit_code, signal)
    FAILED = "failed"  # could not be started, or not ready within its start-up timeout

    @property
    def is_alive(self) -> bool:
        return self in (Lifecycle.STARTING, Lifecycle.READY, Lifecycle.PAUSED, Lifecycle.STOPPING)


class Command(enum.Enum):
    """The verbs of a request on ``component/<name>/cmd``: ``{"cmd": verb, ...}``.

    Each verb's fields, and the reply, are declared in :mod:`executive.bus.api.components`
    (:class:`~executive.bus.api.component_commands.ComponentCommand`).
    """

    CONFIGURE = "configure"
    START = "start"
    PAUSE = "pause"
    RESUME = "resume"
    RECONFIGURE = "reconfigure"
    STOP = "stop"
    GOAL = "goal"
    CANCEL = "cancel"
    INJECT_FAULT = "inject_fault"


class ComponentPhase(enum.Enum):
    """Where a component is in its lifecycle, as the component itself sees it."""

    CREATED = "created"
    CONFIGURED = "configured"
    RUNNING = "running"
    PAUSED = "paused"
    STOPPED = "stopped"


class GoalStatus(enum.Enum):
    SUCCEEDED = "succeeded"
    FAILED = "failed"
    CANCELLED = "cancelled"
