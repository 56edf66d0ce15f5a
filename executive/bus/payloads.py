"""The payloads every service agrees on: what is published on the bus keys of
:mod:`executive.bus.keys`, as typed frozen dataclasses with their JSON forms (an event
on ``events`` is the knowledge base's :class:`~knowledge.records.Event`:
:func:`read_event`; a diagnosis result on ``diagnoses`` is a report of the diagnosis
engine, :class:`executive.bus.reports.DiagnosisInfo`, named here too)."""

from __future__ import annotations

from typing import Any

from executive.bus.reports import DIAGNOSIS_STATUSES, DiagnosisInfo
from executive.bus.schema import Payload, PayloadError, Text, read_record
from executive.bus.states import GoalStatus, Lifecycle
from knowledge.record_class import record
from knowledge.records import Event

__all__ = [  # the diagnosis result is a report (executive.bus.reports), named here too
    "DIAGNOSIS_STATUSES",
    "GENERAL_ERROR",
    "GENERAL_OK",
    "NOT_AVAILABLE",
    "NO_STATE_FITS",
    "TIMEOUT",
    "ComponentState",
    "DiagnosisInfo",
    "GoalFeedback",
    "GoalResult",
    "NodeInfo",
    "ObservationInfo",
    "ResourceInfo",
    "read_event",
]


@record
class ComponentState:
    """The payload of ``component/<name>/state``."""

    component: str
    state: Lifecycle
    pid: int | None = None
    exit_code: int | None = None
    signal: int | None = None
    reason: str = ""
    stamp: float = 0.0
    output: tuple[str, ...] = ()
    """What its process wrote last when it last failed: the end of its Python traceback
    (kept in its later states until it fails again)."""

    def to_payload(self) -> dict[str, Any]:
        return {
            "component": self.component,
            "state": self.state.value,
            "pid": self.pid,
            "exit_code": self.exit_code,
            "signal": self.signal,
            "reason": self.reason,
            "stamp": self.stamp,
            "output": list(self.output),
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
            output=tuple(str(line) for line in payload.get("output") or ()),
        )


# --- observations (thesis 6.2.1) ---------------------------------------------------------

GENERAL_OK = 0
GENERAL_ERROR = -1
NO_STATE_FITS = -2
NOT_AVAILABLE = -3
TIMEOUT = -4


@record
class ObservationInfo:
    """The payload of ``observations``: what one observer saw of its resources.

    ``resource`` lists the observed topics and/or nodes: one topic or node for most
    observer types, two topics for timing, two topics and optionally a behavior for
    movement. ``callerids`` restricts a topic observation to those publishers (empty:
    all of them). A negative ``observation`` is a fault.
    """

    type: str
    resource: tuple[str, ...]
    observation: int
    observation_msg: str = ""
    verbose_observation_msg: str = ""
    callerids: tuple[str, ...] = ()
    stamp: float = 0.0

    @property
    def failed(self) -> bool:
        return self.observation < 0

    def to_payload(self) -> dict[str, Any]:
        return {
            "type": self.type,
            "resource": list(self.resource),
            "observation": self.observation,
            "observation_msg": self.observation_msg,
            "verbose_observation_msg": self.verbose_observation_msg,
            "callerids": list(self.callerids),
            "stamp": self.stamp,
        }

    @classmethod
    def from_payload(cls, payload: dict[str, Any]) -> ObservationInfo:
        """Read a payload; a single resource name is accepted for a list of one.

        Raises ``KeyError``/``ValueError``/``TypeError`` on a malformed payload.
        """
        resource = payload["resource"]
        resources = (resource,) if isinstance(resource, str) else tuple(str(r) for r in resource)
        return cls(
            type=str(payload["type"]),
            resource=resources,
            observation=int(payload["observation"]),
            observation_msg=str(payload.get("observation_msg", "")),
            verbose_observation_msg=str(payload.get("verbose_observation_msg", "")),
            callerids=tuple(str(c) for c in payload.get("callerids", ())),
            stamp=float(payload.get("stamp", 0.0)),
        )


# --- resources (thesis 6.2.4) ------------------------------------------------------------


@record
class NodeInfo:
    """CPU and memory of one component's process tree; ``error`` says it vanished."""

    name: str
    pid: int
    hostname: str
    cpu: float  # percent of one core, summed over the process tree
    memory: int  # resident bytes, summed over the process tree
    error: str = ""

    def to_payload(self) -> dict[str, Any]:
        return {
            "name": self.name,
            "pid": self.pid,
            "hostname": self.hostname,
            "cpu": self.cpu,
            "memory": self.memory,
            "error": self.error,
        }

    @classmethod
    def from_payload(cls, payload: dict[str, Any]) -> NodeInfo:
        return cls(
            str(payload["name"]),
            int(payload["pid"]),
            str(payload["hostname"]),
            float(payload["cpu"]),
            int(payload["memory"]),
            str(payload.get("error", "")),
        )


# The payload of ``resources``: {"stamp": float, "hostname": str, "nodes": [NodeInfo payloads]}


@record
class ResourceInfo:
    """The payload of ``resources``, published by the resource monitor at its rate."""

    hostname: str
    nodes: tuple[NodeInfo, ...]
    stamp: float = 0.0

    def to_payload(self) -> dict[str, Any]:
        return {
            "stamp": self.stamp,
            "hostname": self.hostname,
            "nodes": [n.to_payload() for n in self.nodes],
        }

    @classmethod
    def from_payload(cls, payload: dict[str, Any]) -> ResourceInfo:
        return cls(
            str(payload["hostname"]),
            tuple(NodeInfo.from_payload(n) for n in payload["nodes"]),
            float(payload.get("stamp", 0.0)),
        )


@record
class GoalResult:
    """The payload of ``component/<name>/result``: how a behavior's goal ended.

    Published by the behavior; the launcher stores it as a return value in the KB.
    When a behavior process ends with a goal still open, the launcher makes the result
    itself (FAILED, or CANCELLED if it was asked to stop).

    ``fault``: a FAILED goal failed by a fault of the behavior (an exception, a crash, a
    timeout), not in the world (the SDK's ``GoalFailed``: the planner plans again, the
    behavior is not restarted).
    """

    component: str
    goal_id: str
    status: GoalStatus
    value: dict[str, Any]
    reason: str = ""
    stamp: float = 0.0
    fault: bool = True

    def to_payload(self) -> dict[str, Any]:
        return {
            "component": self.component,
            "goal_id": self.goal_id,
            "status": self.status.value,
            "value": self.value,
            "reason": self.reason,
            "stamp": self.stamp,
            "fault": self.fault,
        }

    @classmethod
    def from_payload(cls, payload: dict[str, Any]) -> GoalResult:
        value = payload.get("value") or {}
        if not isinstance(value, dict):
            raise ValueError(f"result value must be an object, not {type(value).__name__}")
        return cls(
            str(payload["component"]),
            str(payload["goal_id"]),
            GoalStatus(payload["status"]),
            value,
            str(payload.get("reason", "")),
            float(payload.get("stamp", 0.0)),
            bool(payload.get("fault", True)),
        )


@record
class GoalFeedback(Payload):
    """The payload of ``component/<name>/feedback``, published while a goal runs."""

    component: Text
    goal_id: Text
    feedback: dict[str, Any]


# ``ObservationInfo.type`` is an observer type's canonical name: resources, component,
# frequency, timeout, timing, timestamp, scores, movement (configurations may also say
# activated, hz, value, velocity), or a plugin's type.


def read_event(payload: object) -> Event | None:
    """The payload of ``events`` (an event the knowledge base logged) as its record;
    ``None`` if it is not one."""
    try:
        return read_record(Event, payload)
    except PayloadError:
        return None
