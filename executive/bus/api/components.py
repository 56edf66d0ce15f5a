"""The launcher's API: component processes (list, start, stop, logs, achievements, fault
injection). The lifecycle commands every component process serves are in
:mod:`executive.bus.api.component_commands`."""

from __future__ import annotations

from dataclasses import field
from typing import Annotated

from executive.bus.api.free_form import Value
from executive.bus.keys import api
from executive.bus.payloads import ComponentState
from executive.bus.reports import ComponentEntry
from executive.bus.schema import Between, Payload, Text
from executive.bus.verb import Empty, Verb
from knowledge.record_class import record

MAX_LOG_LINES = 10_000


@record
class ComponentName(Payload):
    """A component, by name."""

    name: Text


@record
class ComponentsReply(Payload):
    """Each component as lists show it."""

    components: list[ComponentEntry]


@record
class LogQuery(Payload):
    """The last ``lines`` lines of a component's log."""

    name: Text
    lines: Annotated[int, Between(0, MAX_LOG_LINES)] = 50


@record
class LogReply(Payload):
    """The last lines of a component's log, and where the log is."""

    name: str
    path: str
    lines: list[str]


@record
class Achievement(Payload):
    """A behavior's achievement, kept for a warm start."""

    component: Text
    key: Text
    value: Value = None


@record
class Injection(Payload):
    """A fault to inject into a running component: a mode of the SDK's fault injection
    (:mod:`executive.sdk.fault_injection`) and its options (numbers)."""

    name: Text
    mode: Text
    options: dict[str, Value] = field(default_factory=dict)


def lifecycle(entry: ComponentEntry) -> ComponentState:
    """A listed component's state as ``component/<name>/state`` reports it."""
    return ComponentState(
        entry.component, entry.state, entry.pid, entry.exit_code, entry.signal, entry.reason,
        entry.stamp, entry.output,
    )  # fmt: skip


COMPONENT_LIST = Verb(api("component/list"), Empty, ComponentsReply, threaded=False)
COMPONENT_START = Verb(api("component/start"), ComponentName, ComponentState, timeout=60.0)
COMPONENT_STOP = Verb(api("component/stop"), ComponentName, ComponentState, timeout=60.0)
COMPONENT_LOGS = Verb(api("component/logs"), LogQuery, LogReply, threaded=False)
# asked on component/achieve/<name>: a component stores achievements for itself only
COMPONENT_ACHIEVE = Verb(
    api("component/achieve"), Achievement, Empty, timeout=5.0, caller="component"
)
COMPONENT_INJECT = Verb(api("component/inject"), Injection, ComponentState, timeout=10.0)
