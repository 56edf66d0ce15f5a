"""Typed payloads: frozen dataclasses read from JSON objects by their annotations.

A request or reply of a service's bus API is a :class:`Payload`: a dataclass whose
fields say what a valid JSON object holds. :meth:`Payload.from_payload` reads it with
dura's one reader (:mod:`knowledge.typed_reader`) and refuses bad input with one
sentence that names the field and the bad value; an unknown key is ignored (a newer
sender). Annotations: those of the reader, e.g. ``str``, ``int`` (within 64 bits),
``float`` (finite; an integer is accepted), ``bool``, ``X | None``, ``list[X]``,
``tuple[X, ...]``, ``dict[str, X]``, ``Any``, an enum (by value), a nested dataclass
(a :class:`Payload`, or a record of :mod:`knowledge.records`), and ``Annotated[X, ...]``
with :class:`NonEmpty` and :class:`Between`. A field with a default may be absent;
``None`` means absent too.

Payload classes are records (:func:`knowledge.record_class.record`): frozen dataclasses
(assigning a field raises :class:`dataclasses.FrozenInstanceError`) whose constructor,
comparison, hash, repr and immutability are shared by every record class, not generated
and compiled for each.
"""

from __future__ import annotations

import dataclasses
import enum
import json
from collections.abc import Callable, Mapping, Sequence
from typing import Annotated, Any, Self, TypeVar

from knowledge.conventions import Between, NonEmpty
from knowledge.errors import DuraError
from knowledge.field_plan import MISSING, PathPart
from knowledge.typed_reader import (
    Entry,
    Place,
    Source,
    open_entry,
    read_entry,
    read_value,
)

__all__ = [
    "Between",
    "NonEmpty",
    "Payload",
    "PayloadError",
    "Text",
    "plain",
    "read",
    "read_record",
    "shown",
]

T = TypeVar("T")
R = TypeVar("R")


class PayloadError(DuraError):
    """A payload that does not fit its type."""


Text = Annotated[str, NonEmpty()]


def shown(value: Any) -> str:
    """A value as JSON (as the sender wrote it), cut short if long."""
    try:
        text = json.dumps(value)
    except (TypeError, ValueError):
        text = repr(value)
    return text if len(text) <= 60 else text[:57] + "..."


def _name(path: Sequence[PathPart]) -> str:
    """A field's place in a payload: ``inner.name``, ``colors[0]``."""
    out = ""
    for part in path:
        out += f"[{part}]" if isinstance(part, int) else (f".{part}" if out else part)
    return out


class PayloadSource(Source):
    """JSON objects from the bus: the first problem raises :class:`PayloadError`, values
    show as JSON, unknown keys are ignored, numbers are JSON's (finite, 64 bits)."""

    report_unknown = False
    strict_numbers = True
    names_items = False

    def error(self, line: int | None, message: str) -> None:
        raise PayloadError(message)

    def first_that_reads(self, reads: Sequence[Callable[[], Any]]) -> Any:
        """Each option in turn until one reads the value; the first one's problem if none
        does (``list[Task] | Unanswered``: an object is tried as each record)."""
        problems: list[PayloadError] = []
        for read in reads:
            try:
                return read()
            except PayloadError as e:
                problems.append(e)
        raise problems[0]

    def describe(self, value: Any, path: Sequence[PathPart]) -> str:
        return shown(value)

    def subject(self, place: Place) -> str:
        return f"'{_name(place.path)}'"

    def wrong(self, place: Place, expected: str, value: Any) -> Any:
        raise PayloadError(f"{self.subject(place)} must be {expected}, not {shown(value)}")

    def not_mapping(
        self, what: str, place: Place | None, path: Sequence[PathPart], line: int | None, value: Any
    ) -> None:
        raise PayloadError(f"'{_name(path)}' must be an object, not {shown(value)}")

    def missing(self, entry: Entry, key: str, annotation: Any) -> Any:
        return read_value(annotation, None, Place(entry, key, (*entry.path, key)))

    def empty(self, place: Place) -> None:
        """An empty list is a list: its annotation says whether it may be."""

    def expected_list(self, item: Any, names: bool) -> str:
        return "a list"

    def expected_mapping(self, named: bool) -> str:
        return "an object"


_SOURCE = PayloadSource()


class Payload:
    """A frozen dataclass that is a JSON object on the bus (subclasses are dataclasses)."""

    @classmethod
    def from_payload(cls, payload: Mapping[str, Any], *, prefix: str = "") -> Self:
        """Read and check a JSON object; unknown keys are ignored (newer senders).
        ``prefix`` names where the object is in an enclosing one (``inner.``).

        Raises:
            PayloadError: a field is missing or does not fit its annotation.
        """
        return read_record(cls, payload, prefix)

    def to_payload(self) -> dict[str, Any]:
        """The JSON object; an optional field left at ``None`` is not sent (absent reads
        back as its default)."""
        return {
            f.name: plain(value)
            for f in dataclasses.fields(self)  # type: ignore[arg-type]
            if (value := getattr(self, f.name)) is not None or f.default is dataclasses.MISSING
        }


def read_record(cls: type[R], payload: Any, prefix: str = "") -> R:
    """A JSON object read as ``cls``: a :class:`Payload`, or a record that travels on its
    own (a frozen dataclass, such as an event of :mod:`knowledge.records` on ``events``).
    ``prefix`` names where the object is in an enclosing one (``inner.``).

    Raises:
        PayloadError: it is not an object, or a field is missing or does not fit.
    """
    path = tuple(p for p in prefix.split(".") if p)
    entry = open_entry(payload, _SOURCE, path)
    found = read_entry(cls, entry) if entry is not None else MISSING
    if found is MISSING:
        raise PayloadError(f"'{_name(path)}' is not a valid {cls.__name__}")
    return found  # type: ignore[no-any-return]


def read(annotation: Any, value: Any, name: str = "value") -> Any:
    """A JSON value read as a payload's field of that annotation would be (a record, a
    list of records, ...); ``name`` names it in a message.

    Raises:
        PayloadError: it does not fit.
    """
    return Entry({name: value}, _SOURCE).read(name, annotation, required=True)


def plain(value: Any) -> Any:
    """A field's value as JSON data."""
    if isinstance(value, Payload):
        return value.to_payload()
    if isinstance(value, enum.Enum):
        return value.value
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        return {f.name: plain(getattr(value, f.name)) for f in dataclasses.fields(value)}
    if isinstance(value, list | tuple):
        return [plain(v) for v in value]
    if isinstance(value, Mapping):
        return {k: plain(v) for k, v in value.items()}
    return value
