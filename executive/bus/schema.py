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

Payload classes are declared with :func:`payload`: frozen dataclasses (assigning a field
raises :class:`dataclasses.FrozenInstanceError`) whose constructor, comparison, hash,
repr and immutability are shared by every payload class, not generated and compiled
for each: defining one costs a tenth of what a frozen dataclass costs, and a command
loads tens of them (see :func:`payload`).
"""

from __future__ import annotations

import dataclasses
import enum
import json
import operator
import reprlib
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import Annotated, Any, Self, TypeVar, dataclass_transform

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
    "payload",
    "plain",
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


# --- payload classes: frozen, with their methods shared ---------------------------------


@dataclass_transform(frozen_default=True, field_specifiers=(dataclasses.field,))
def payload(cls: type[T]) -> type[T]:
    """A payload class: a frozen dataclass, compared, hashed and shown by its fields (a
    class that defines its own comparison, hash or repr keeps it).

    Its constructor, comparison, hash, repr and its refusal to change a field are shared
    by every payload class, not generated and compiled for each as by
    ``dataclass(frozen=True)``: a class costs about 0.03 ms to create instead of 0.3
    (0.15 for a dataclass that is not frozen), and a quick command loads tens of them;
    making an instance costs about 0.9 µs instead of 0.4. A class the shared constructor
    cannot make (keyword-only, ``InitVar`` or ``init=False`` fields, a ``__post_init__``,
    dataclass bases) is made by ``dataclass(frozen=True)``."""
    if not _plain(cls):
        made: Any = dataclass(frozen=True, eq=False, repr=False)(cls)
    else:
        made = dataclass(init=False, eq=False, repr=False)(cls)
        made._payload_init = _InitPlan(made.__qualname__, dataclasses.fields(made))
        for name in ("__init__", "__setattr__", "__delattr__", "__signature__"):
            setattr(made, name, _Frozen.__dict__[name])
        made.__dataclass_params__.frozen = True
    made._payload_values = _getter(tuple(f.name for f in dataclasses.fields(made) if f.compare))
    for name in ("__eq__", "__hash__", "__repr__"):
        if made.__dict__.get(name) is None:
            setattr(made, name, getattr(_ByFields, name))
    return made  # type: ignore[no-any-return]


def _own_annotations(cls: type) -> dict[str, Any]:
    """A class's own annotations, as written (``inspect`` is not imported for them)."""
    found: dict[str, Any] = cls.__dict__.get("__annotations__", {})  # noqa: RUF063
    return found


def _plain(cls: type) -> bool:
    """Whether the shared constructor makes a class: its fields are all positional, and
    it has no ``__post_init__`` nor dataclass bases."""
    if hasattr(cls, "__post_init__") or any(dataclasses.is_dataclass(b) for b in cls.__mro__[1:]):
        return False
    for name, annotation in _own_annotations(cls).items():
        if any(word in str(annotation) for word in ("KW_ONLY", "InitVar")):
            return False
        value = cls.__dict__.get(name)
        if isinstance(value, dataclasses.Field) and (not value.init or value.kw_only is True):
            return False
    return True


class _InitPlan:
    """What the shared constructor of one payload class needs: its fields in order, the
    defaults of those that have one."""

    __slots__ = ("defaults", "names", "qualname")

    def __init__(self, qualname: str, fields: tuple[dataclasses.Field[Any], ...]) -> None:
        self.qualname = qualname
        self.names = tuple(f.name for f in fields)
        self.defaults: dict[str, tuple[bool, Any]] = {}  # name -> (is a factory, value)
        for f in fields:
            if f.default is not dataclasses.MISSING:
                self.defaults[f.name] = (False, f.default)
            elif f.default_factory is not dataclasses.MISSING:
                self.defaults[f.name] = (True, f.default_factory)


_set = object.__setattr__


class _Signature:
    """The constructor's signature, for ``inspect.signature`` and ``help`` (made when
    asked: ``inspect`` is not imported before)."""

    def __get__(self, instance: object, owner: type) -> Any:
        import inspect

        plan: _InitPlan = owner._payload_init  # type: ignore[attr-defined]
        parameters = []
        for name in plan.names:
            default = inspect.Parameter.empty
            if name in plan.defaults:
                factory, value = plan.defaults[name]
                default = value() if factory else value
            parameters.append(
                inspect.Parameter(name, inspect.Parameter.POSITIONAL_OR_KEYWORD, default=default)
            )
        return inspect.Signature(parameters, return_annotation=None)


class _Frozen:
    """The constructor and the immutability of every payload class."""

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        plan: _InitPlan = self.__class__._payload_init  # type: ignore[attr-defined]
        names = plan.names
        if len(args) > len(names):
            raise TypeError(
                f"{plan.qualname}() takes {len(names)} positional arguments but "
                f"{len(args)} were given"
            )
        for name, value in zip(names, args, strict=False):
            _set(self, name, value)
        for name in names[len(args) :]:
            if name in kwargs:
                _set(self, name, kwargs.pop(name))
            elif name in plan.defaults:
                factory, value = plan.defaults[name]
                _set(self, name, value() if factory else value)
            else:
                raise TypeError(f"{plan.qualname}() missing the argument '{name}'")
        if kwargs:
            name = next(iter(kwargs))
            twice = name in names
            raise TypeError(
                f"{plan.qualname}() got {'multiple values for' if twice else 'an unexpected'} "
                f"argument '{name}'"
            )

    def __setattr__(self, name: str, value: Any) -> None:
        raise dataclasses.FrozenInstanceError(f"cannot assign to field '{name}'")

    def __delattr__(self, name: str) -> None:
        raise dataclasses.FrozenInstanceError(f"cannot delete field '{name}'")

    __signature__ = _Signature()


def _getter(names: tuple[str, ...]) -> Callable[[Any], tuple[Any, ...]]:
    """The values of these fields of a payload, as a tuple."""
    if len(names) > 1:
        return operator.attrgetter(*names)  # a tuple of them, at C speed
    if names:
        (name,) = names
        return lambda value: (getattr(value, name),)
    return lambda value: ()


def _compared(value: Any) -> tuple[Any, ...]:
    compared: tuple[Any, ...] = value.__class__._payload_values(value)
    return compared


class _ByFields:
    """The comparison, hash and repr of every payload class, by its fields."""

    def __eq__(self, other: object) -> bool:
        if other.__class__ is not self.__class__:
            return NotImplemented
        return _compared(self) == _compared(other)

    def __hash__(self) -> int:
        return hash(_compared(self))

    @reprlib.recursive_repr()
    def __repr__(self) -> str:
        fields = dataclasses.fields(self)  # type: ignore[arg-type]
        shown = ", ".join(f"{f.name}={getattr(self, f.name)!r}" for f in fields if f.repr)
        return f"{self.__class__.__qualname__}({shown})"
