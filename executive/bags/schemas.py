"""JSON schemas of the payloads dura records (MCAP schema encoding ``jsonschema``), made
from the payload dataclasses themselves, so that they never drift from them.

Each recorded bus key has one schema: ``topic/<name>`` component data (a JSON object
with a ``stamp``; components add what they like), ``observations``, ``diagnoses``,
``resources``, ``events`` and ``component/<name>/state``.
"""

from __future__ import annotations

import dataclasses
import enum
import json
import types
import typing
from collections.abc import Mapping
from typing import Any

from executive.bus.keys import DIAGNOSES, EVENTS, OBSERVATIONS, RESOURCES
from executive.bus.payloads import ComponentState, DiagnosisInfo, ObservationInfo, ResourceInfo
from knowledge.records import Event

SCHEMA = "https://json-schema.org/draft/2020-12/schema"


def _type(annotation: Any) -> dict[str, Any]:
    """Return the JSON schema of one annotated field."""
    origin = typing.get_origin(annotation)
    if annotation is Any:
        return {}
    if origin in (types.UnionType, typing.Union):
        return {"anyOf": [_type(a) for a in typing.get_args(annotation)]}
    if annotation is type(None):
        return {"type": "null"}
    simple = {str: "string", bool: "boolean", int: "integer", float: "number"}
    if annotation in simple:
        return {"type": simple[annotation]}
    if origin in (list, tuple):
        return {"type": "array", "items": _type(typing.get_args(annotation)[0])}
    if origin in (dict, Mapping) or annotation in (dict, Mapping):
        args = typing.get_args(annotation)
        return {"type": "object", "additionalProperties": _type(args[1]) if args else {}}
    if isinstance(annotation, type) and issubclass(annotation, enum.Enum):
        return {"type": "string", "enum": [m.value for m in annotation]}
    if dataclasses.is_dataclass(annotation) and isinstance(annotation, type):
        return object_schema(annotation)
    raise TypeError(f"no JSON schema for the annotation {annotation!r}")


def object_schema(cls: type, extra: Mapping[str, Any] | None = None) -> dict[str, Any]:
    """Return the schema of a payload dataclass (its fields, all required) plus ``extra``."""
    hints = typing.get_type_hints(cls)
    fields = [f.name for f in dataclasses.fields(cls)]
    properties = {name: _type(hints[name]) for name in fields}
    return {
        "type": "object",
        "title": cls.__name__,
        "properties": {**properties, **(extra or {})},
        "required": fields,
    }


def _schema(cls: type, extra: Mapping[str, Any] | None = None) -> dict[str, Any]:
    return {"$schema": SCHEMA, **object_schema(cls, extra)}


TOPIC_MESSAGE = {
    "$schema": SCHEMA,
    "type": "object",
    "title": "TopicMessage",
    "description": "component data on topic/<name>: any JSON object, stamped",
    "properties": {"stamp": {"type": "number"}},
}

# The payloads of the recorded keys, by schema name.
SCHEMAS: dict[str, dict[str, Any]] = {
    "dura.TopicMessage": TOPIC_MESSAGE,
    "dura.Observation": _schema(
        ObservationInfo,
        {
            "values": {"type": "object", "additionalProperties": {"type": "number"}},
            "observer": {"type": "string"},
        },
    ),
    "dura.Diagnosis": _schema(DiagnosisInfo),
    "dura.Resources": _schema(ResourceInfo),
    "dura.Event": _schema(Event),
    "dura.ComponentState": _schema(ComponentState),
}
BY_KEY = {
    OBSERVATIONS: "dura.Observation",
    DIAGNOSES: "dura.Diagnosis",
    RESOURCES: "dura.Resources",
    EVENTS: "dura.Event",
}


def schema_name(key: str) -> str | None:
    """Return the schema of a bus key's payloads; ``None`` for keys dura does not record."""
    if key.startswith("topic/"):
        return "dura.TopicMessage"
    parts = key.split("/")
    if len(parts) == 3 and parts[0] == "component" and parts[2] == "state":
        return "dura.ComponentState"
    return BY_KEY.get(key)


def schema_bytes(name: str) -> bytes:
    return json.dumps(SCHEMAS[name], sort_keys=True).encode()
