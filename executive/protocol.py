"""The bus protocol: key names and the payloads every service agrees on.

Keys are relative to ``dura/<robot>/``. A service that owns a key documents its
payload here, so that each service can run in its own process (or on another
machine) and still understand the others.
"""

from __future__ import annotations

import enum
from dataclasses import dataclass
from typing import Any

OBSERVATIONS = "observations"  # observation infos from observers (monitoring issue)
DIAGNOSES = "diagnoses"  # diagnosis results (diagnosis engine)
RESOURCES = "resources"  # resource monitor node infos
EXECUTIVE_ALIVE = "alive/executive"  # liveliness token of the executive process
EVENTS = "events"  # every KB event, as it is logged


def topic(name: str) -> str:
    """Component data on a named topic."""
    return f"topic/{name.strip('/')}"


def component(name: str, leaf: str) -> str:
    """``component/<name>/<leaf>``; leaves: cmd, state, result, feedback."""
    return f"component/{name}/{leaf}"


def api(verb: str) -> str:
    """A request the CLI (or another service) makes of the executive."""
    return f"executive/api/{verb}"


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


@dataclass(frozen=True)
class ComponentState:
    """The payload of ``component/<name>/state``."""

    component: str
    state: Lifecycle
    pid: int | None = None
    exit_code: int | None = None
    signal: int | None = None
    reason: str = ""
    stamp: float = 0.0

    def to_payload(self) -> dict[str, Any]:
        return {
            "component": self.component,
            "state": self.state.value,
            "pid": self.pid,
            "exit_code": self.exit_code,
            "signal": self.signal,
            "reason": self.reason,
            "stamp": self.stamp,
        }

    @classmethod
    def from_payload(cls, payload: dict[str, Any]) -> ComponentState:
        """Read a payload; raises ``KeyError``/``ValueError`` on a malformed one."""
        return cls(
            component=str(payload["component"]),
            state=Lifecycle(payload["state"]),
            pid=payload.get("pid"),
            exit_code=payload.get("exit_code"),
            signal=payload.get("signal"),
            reason=str(payload.get("reason", "")),
            stamp=float(payload.get("stamp", 0.0)),
        )
