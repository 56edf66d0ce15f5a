"""How each field of a schema is read: its key, default, and conventions (the plan).

:func:`fields_of` works out, once per dataclass, what its annotations and their
``Annotated`` metadata (:mod:`knowledge.conventions`) say about each field; the helpers
below take annotations apart for :mod:`knowledge.typed_reader`.
"""

from __future__ import annotations

import dataclasses
import enum
import sys
import types
import typing
from collections.abc import Callable, Iterator, Mapping, Sequence
from typing import TYPE_CHECKING, Any

from knowledge.conventions import (
    AllLines,
    Default,
    EntryLine,
    FromKey,
    Key,
    KeyLines,
    Label,
    Required,
    Titles,
    When,
    Whole,
)

if TYPE_CHECKING:
    from knowledge.typed_reader import Entry


class _Missing:
    def __repr__(self) -> str:
        return "MISSING"


MISSING: Any = _Missing()
"""What a read gives when there is no valid value (the problem is reported)."""

PathPart = str | int


def dotted(path: Sequence[PathPart]) -> str:
    """A path as line lookups key it: ``topics.0.filter``."""
    return ".".join(str(p) for p in path)


def split(annotation: Any) -> tuple[Any, tuple[Any, ...]]:
    """An annotation without ``Annotated``, and the metadata it had."""
    if typing.get_origin(annotation) is typing.Annotated:
        return annotation.__origin__, tuple(annotation.__metadata__)
    return annotation, ()


def has(meta: tuple[Any, ...], kind: type) -> bool:
    """Whether the metadata holds a marker of a kind."""
    return any(isinstance(m, kind) for m in meta)


def sequence(base: Any) -> bool:
    """Whether an annotation (without metadata) is a list or tuple."""
    return typing.get_origin(base) in (list, tuple, Sequence)


def without_none(annotation: Any) -> Any:
    """``X`` for ``X | None``; else the annotation."""
    if typing.get_origin(annotation) in (types.UnionType, typing.Union):
        options = [o for o in typing.get_args(annotation) if o is not type(None)]
        if len(options) == 1:
            return options[0]
    return annotation


def entries_of(annotation: Any) -> bool:
    """Whether an annotation is a list of entries (of dataclasses, or labelled)."""
    outer, meta = split(annotation)
    base = split(without_none(outer))[0]
    if not sequence(base):
        return False
    item = split(typing.get_args(base)[0])[0]
    return has(meta, Label) or dataclasses.is_dataclass(typing.get_origin(item) or item)


class FieldSpec:
    """How one field of a schema is read: its document ``key``, its ``default`` (a
    function giving it, or :data:`MISSING`), whether its absence is reported, the
    template it ``titles`` its entry with, the field it depends on (``when``), and
    what it is filled from instead (``fill``: FromKey, EntryLine, KeyLines, ...)."""

    __slots__ = (
        "annotation", "default", "fill", "key", "name", "old", "required", "titles", "when",
    )  # fmt: skip

    def __init__(self, name: str, annotation: Any, default: Any) -> None:
        meta = split(annotation)[1]
        self.name = name
        self.annotation = annotation
        given = next((m for m in meta if isinstance(m, Default)), None)
        self.default = _constant(given.value) if given is not None else default
        key = next((m for m in meta if isinstance(m, Key)), None)
        self.key = key.name if key is not None else name
        self.old = key.old if key is not None else ()
        self.required = any(isinstance(m, Required) for m in meta)
        self.titles = next((m for m in meta if isinstance(m, Titles)), None)
        self.when = next((m for m in meta if isinstance(m, When)), None)
        fills = (FromKey, EntryLine, KeyLines, Whole, AllLines)
        self.fill = next((m for m in meta if isinstance(m, fills)), None)


_PLANS: dict[type, tuple[FieldSpec, ...]] = {}  # worked out once per class


class _ModuleNames(Mapping[str, Any]):
    """The names of a module as its attributes: a module may import the types of its
    annotations when they are first asked for (a module ``__getattr__``, PEP 562)."""

    def __init__(self, module: object) -> None:
        self.module = module

    def __getitem__(self, name: str) -> Any:
        try:
            return getattr(self.module, name)
        except AttributeError:
            raise KeyError(name) from None

    def __iter__(self) -> Iterator[str]:
        return iter(())

    def __len__(self) -> int:
        return 0


def fields_of(cls: type) -> tuple[FieldSpec, ...]:
    """How each field of a dataclass is read (worked out once per class)."""
    known = _PLANS.get(cls)
    if known is not None:
        return known
    names = _ModuleNames(sys.modules[cls.__module__])
    hints = typing.get_type_hints(cls, localns=names, include_extras=True)
    plan: list[FieldSpec] = []
    for f in dataclasses.fields(cls):
        if not f.init:
            continue
        default: Any = MISSING
        if f.default is not dataclasses.MISSING:
            default = _constant(f.default)
        elif f.default_factory is not dataclasses.MISSING:
            default = f.default_factory
        plan.append(FieldSpec(f.name, hints[f.name], default))
    known = _PLANS[cls] = tuple(plan)
    return known


def _constant(value: Any) -> Callable[[], Any]:
    return lambda: value


def filled(fill: object, entry: Entry) -> Any:
    """The value of a field filled from its entry (``fill``: FromKey, EntryLine, ...)."""
    if isinstance(fill, FromKey):
        return entry.name if entry.name is not None else MISSING
    if isinstance(fill, EntryLine):
        return entry.line or 0
    if isinstance(fill, Whole):
        return dict(entry.written)
    if isinstance(fill, KeyLines):
        lines = {k: entry.key_line(k) or 0 for k in entry.written}
        for key in fill.nested:
            inner = entry.written.get(key)
            for k in inner if isinstance(inner, Mapping) else ():
                found = entry.source.key_line((*entry.path, key, str(k)))
                lines[f"{key}.{k}"] = found if found is not None else lines[key]
        return lines
    lines = {}  # AllLines
    stack: list[tuple[tuple[PathPart, ...], Any]] = [((), entry.written)]
    while stack:
        relative, value = stack.pop()
        children = value.items() if isinstance(value, Mapping) else enumerate(value)
        for k, v in children:
            path = (*relative, str(k))
            line = entry.source.key_line((*entry.path, *path))
            if line is not None:
                lines[dotted(path)] = line
            if isinstance(v, Mapping | list):
                stack.append((path, v))
    return lines


def fits(option: Any, value: Any) -> bool:
    """Whether a value is of the kind that an option of a union reads."""
    base = split(option)[0]
    kinds: dict[Any, Callable[[Any], bool]] = {
        Any: lambda v: True,
        bool: lambda v: isinstance(v, bool),
        int: lambda v: isinstance(v, int) and not isinstance(v, bool),
        float: lambda v: isinstance(v, int | float) and not isinstance(v, bool),
        str: lambda v: isinstance(v, str),
    }
    if base in kinds:
        return kinds[base](value)
    if sequence(base):
        return isinstance(value, list | tuple)
    if isinstance(base, type) and issubclass(base, enum.Enum):
        return any(m.value == value for m in base)
    return isinstance(value, Mapping)


def expected(option: Any) -> str:
    """How a message names what an option of a union takes."""
    base = split(option)[0]
    names = {str: "a string", bool: "true or false", int: "an integer", float: "a number"}
    if base in names:
        return names[base]
    if sequence(base):
        return "a list"
    if isinstance(base, type) and issubclass(base, enum.Enum):
        return "one of " + ", ".join(str(m.value) for m in base)
    return "an object"
