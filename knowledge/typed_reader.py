"""Read plain values into annotated frozen dataclasses, with the place of every problem.

One reader for robot descriptions, observer configurations and bus payloads. A schema
is a frozen dataclass; each field's annotation says what a valid value is: ``str``,
``int``, ``float``, ``bool``, :class:`~pathlib.Path`, an :class:`enum.Enum` (by value),
``X | None``, a union such as ``bool | float`` (the first that fits), ``list[X]``,
``tuple[X, ...]``, ``Mapping[str, X]`` (or ``dict``), ``Any``, or another dataclass (a
nested entry). A field without a default must be given. ``Annotated`` metadata adds
constraints and conventions (:mod:`knowledge.conventions` lists them): bounds, non-empty
texts and lists, choices, a single value as a list of one, names, mappings of names to
entries, the document's key of a field, fields filled from the entry's name or lines, how
messages name an entry, and functions that check or read a field.

A dataclass may define ``after_read(self, entry) -> Self | None`` for the checks across
its fields (problems reported on the :class:`Entry`; ``None`` refuses the entry). Where
values come from, and how their problems are worded, is a
:class:`~knowledge.value_source.Source`.
"""

from __future__ import annotations

import dataclasses
import enum
import math
import re
import types
import typing
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import Any

from knowledge.conventions import (
    Bound,
    Check,
    Convert,
    Exists,
    Label,
    Named,
    Names,
    NonEmpty,
    Nullable,
    OneOf,
    OneOrMore,
    Open,
    OrDefault,
    Tagged,
)
from knowledge.errors import did_you_mean
from knowledge.field_plan import (
    MISSING,
    FieldSpec,
    PathPart,
    entries_of,
    expected,
    fields_of,
    filled,
    fits,
    has,
    split,
)
from knowledge.value_source import Place, Source

__all__ = [
    "MISSING",
    "Entry",
    "Place",
    "Source",
    "open_entry",
    "read",
    "read_entry",
    "read_inline",
    "read_value",
]


class Entry:
    """One mapping being read: its keys, what messages call it (``what``), its place.

    Keys are read with :meth:`read` or, for a dataclass, :meth:`read_fields`;
    :meth:`close` reports every key no read asked for. ``owner`` is what messages called
    the enclosing entry; ``name`` the entry's key in a mapping of names.
    """

    def __init__(
        self,
        value: Mapping[Any, Any],
        source: Source,
        path: tuple[PathPart, ...] = (),
        what: str = "",
        line: int | None = None,
        *,
        owner: str = "",
        name: str | None = None,
    ) -> None:
        self.source = source
        self.path = path
        self.what = what
        self.owner = owner
        self.name = name
        self.line = line if line is not None else source.value_line(path)
        self.written: dict[str, Any] = {str(k): v for k, v in value.items()}
        self.values: dict[str, Any] = {}  # the fields read so far, by name
        self.schema: type | None = None  # the dataclass being read
        self.titled = False  # a field has named the entry (the first to do so counts)
        self._known: set[str] = set()

    def has(self, key: str) -> bool:
        """Whether a key is written (with any value, null too)."""
        return key in self.written

    def _present(self, key: str) -> bool:
        """Whether a key has a value to read (a null is none where null means absent)."""
        if key not in self.written:
            return False
        return self.written[key] is not None or not self.source.null_is_absent

    def key_line(self, key: str) -> int | None:
        """The line of one of the entry's keys (the entry's own if it is absent)."""
        if key not in self.written:
            return self.line
        found = self.source.key_line((*self.path, key))
        return found if found is not None else self.line

    def error(self, key: str | None, message: str) -> None:
        """Report a problem at a key's line (at the entry's line for ``None``)."""
        self.source.error(self.line if key is None else self.key_line(key), message)

    def read(
        self, key: str, annotation: Any, default: Any = MISSING, *, required: bool = False
    ) -> Any:
        """A key's value read against an annotation (the key counts as known).

        An absent key gives ``default`` (reported if ``required``); so does a wrong value
        (reported).
        """
        self._known.add(key)
        if not self._present(key):
            if required:
                found = self.source.missing(self, key, annotation)
                return default if found is MISSING else found
            return default
        place = Place(self, key, (*self.path, key), required=required)
        found = read_value(annotation, self.written[key], place)
        return default if found is MISSING else found

    def known(self, *keys: str) -> None:
        """Count keys as known without reading them."""
        self._known.update(keys)

    def read_fields(self, cls: type, **given: Any) -> dict[str, Any] | None:
        """The values of a dataclass's fields read from this entry (but those ``given``);
        ``None`` if a field without a default has no valid value (reported)."""
        out: dict[str, Any] = {}
        complete = True
        self.schema = cls
        title: tuple[str, str | None] | None = None  # a name for the entry, and from when
        for spec in fields_of(cls):
            if spec.when is not None and self.values.get(spec.when.field) not in spec.when.values:
                continue
            if spec.name in given:
                value = given[spec.name]
            elif spec.fill is not None:
                value = filled(spec.fill, self)
            else:
                required = spec.required or spec.default is MISSING
                value = self.read(self._key(spec), spec.annotation, required=required)
            if value is MISSING:
                if spec.default is MISSING:
                    complete = False
                    continue
                value = spec.default()
            elif spec.titles is not None and title is None and not self.titled:
                self.values[spec.name] = value
                title = self._title(spec.titles.template, value), spec.titles.after
            out[spec.name] = self.values[spec.name] = value
            if title is not None and title[0] and title[1] in (None, spec.name):
                self.what, self.titled = title[0], True
                title = None
        return out if complete else None

    def _title(self, template: str, value: Any) -> str:
        """The entry's name from a template, or ``""`` if a field it names has none."""
        names = {**self.values, "value": value, "owner": self.owner}
        if any(names.get(f) in (None, "") for f in re.findall(r"{(\w+)}", template)):
            return ""
        return template.format_map(names)

    def _key(self, spec: FieldSpec) -> str:
        """The key a field is read from: its key, or an older spelling written instead."""
        if not spec.old:
            return spec.key
        written = [k for k in (spec.key, *spec.old) if self.has(k)]
        if len(written) > 1:
            self.known(written[1])
            self.error(written[1], f"{self.what} has both '{written[0]}' and '{written[1]}'")
        return written[0] if written else spec.key

    def close(self) -> None:
        """Report every key no read asked for (where unknown keys are problems)."""
        if self.source.report_unknown:
            for key in self.written:
                if key not in self._known:
                    self.source.unknown(self, key, list(self._known))


def open_entry(
    value: Any,
    source: Source,
    path: tuple[PathPart, ...] = (),
    what: str = "",
    *,
    place: Place | None = None,
    line: int | None = None,
    name: str | None = None,
) -> Entry | None:
    """An entry for a mapping; ``None`` if the value is no mapping (reported)."""
    if not isinstance(value, Mapping):
        where = line if line is not None else source.value_line(path)
        source.not_mapping(what, place, path, where, value)
        return None
    owner = place.entry.what if place is not None else ""
    return Entry(value, source, path, what, line, owner=owner, name=name)


# --- reading values --------------------------------------------------------------------


def read_value(annotation: Any, value: Any, place: Place) -> Any:
    """A value read against an annotation; :data:`MISSING` if it does not fit (reported)."""
    base, meta = split(annotation)
    for m in meta:
        if isinstance(m, Convert):
            return m.function(value, place)
    return _constrained(meta, _typed(base, meta, value, place), value, place)


def _constrained(meta: tuple[Any, ...], found: Any, value: Any, place: Place) -> Any:
    """A value read, if it meets the constraints of the metadata (else reported)."""
    if found is MISSING or found is None:
        return found
    for m in meta:
        if isinstance(m, Bound) and not isinstance(found, bool) and not m.holds(found):
            return place.source.out_of_bounds(place, m, value, found)
        if isinstance(m, NonEmpty) and not isinstance(found, str) and not found:
            return place.wrong("a non-empty list", value)
        if isinstance(m, OneOf) and found not in m.choices:
            choices = ", ".join(m.choices)
            place.entry.error(
                place.key,
                f"unknown {m.noun} '{found}' in {place.entry.what} (choose from {choices})"
                f"{did_you_mean(found, m.choices)}",
            )
            return MISSING
        if isinstance(m, Exists) and not found.is_file():
            place.entry.error(place.key, m.missing(place.key, value, found, place.source.folder))
        if isinstance(m, Check):
            found = m.function(found, place)
            if found is MISSING:
                return MISSING
    return found


def _typed(base: Any, meta: tuple[Any, ...], value: Any, place: Place) -> Any:
    if base is Any:
        return value
    origin = typing.get_origin(base)
    if origin in (types.UnionType, typing.Union):
        return _union(typing.get_args(base), meta, value, place)
    if base is str:
        return _text(meta, value, place)
    if base is bool:
        return value if isinstance(value, bool) else place.wrong("true or false", value)
    if base is int:
        integer = isinstance(value, int) and not isinstance(value, bool)
        if integer and (not place.source.strict_numbers or -(2**63) <= value < 2**63):
            return value
        return place.wrong("an integer", value)
    if base is float:
        if not isinstance(value, int | float) or isinstance(value, bool):
            return place.wrong("a number", value)
        if place.source.strict_numbers and not math.isfinite(value):
            return place.wrong("a finite number", value)
        return float(value)
    if origin in (list, tuple, Sequence):
        return _list(base, meta, value, place)
    if origin in (dict, Mapping) or base in (dict, Mapping):
        return _mapping(base, meta, value, place)
    if base is Path:
        return _path(value, place)
    if isinstance(base, type) and issubclass(base, enum.Enum):
        try:
            return base(value)
        except (ValueError, TypeError):
            return place.wrong("one of " + ", ".join(str(m.value) for m in base), value)
    if dataclasses.is_dataclass(base) or any(isinstance(m, Tagged) for m in meta):
        return _nested(base, meta, value, place)
    raise TypeError(f"no reader for the annotation {base!r} of '{place.key}'")


def _union(options: tuple[Any, ...], meta: tuple[Any, ...], value: Any, place: Place) -> Any:
    nullable = place.source.null_is_absent or has(meta, Nullable)
    if value is None and type(None) in options and nullable:
        return None
    rest = [o for o in options if o is not type(None)]
    fitting = [o for o in rest if len(rest) == 1 or fits(o, value)]
    if not fitting:
        return place.wrong(" or ".join(expected(o) for o in rest), value)

    def reading(option: Any) -> Callable[[], Any]:
        base, inner = split(option)
        return lambda: _constrained(inner, _typed(base, meta + inner, value, place), value, place)

    return place.source.first_that_reads([reading(o) for o in fitting])


def _text(meta: tuple[Any, ...], value: Any, place: Place) -> Any:
    non_empty = next((m for m in meta if isinstance(m, NonEmpty)), None)
    expected = "a non-empty string" if non_empty else "a string"
    if value == "" and has(meta, OrDefault):
        return MISSING  # the default, and no problem
    if isinstance(value, str):
        if non_empty and not (value if non_empty.blank else value.strip()):
            return place.wrong(expected, value)
        return value
    if value is not None and not isinstance(value, Mapping | list | tuple):
        text = place.source.text(value, place.path)
        if text is not None:
            return text
    return place.wrong(expected, value)


def _path(value: Any, place: Place) -> Any:
    text = _text((), value, place)
    if text is MISSING:
        return MISSING
    path = Path(text).expanduser()
    folder = place.source.folder
    return path if path.is_absolute() or folder is None else (folder / path).resolve()


def _list(base: Any, meta: tuple[Any, ...], value: Any, place: Place) -> Any:
    args = typing.get_args(base)
    if typing.get_origin(base) is tuple and len(args) >= 1 and args[-1] is not Ellipsis:
        return _fixed(args, value, place)
    item_type = args[0] if args else Any
    names = has(meta, Names)
    single = isinstance(value, str) and (names or has(meta, OneOrMore))
    if value is None and not place.source.null_is_absent:
        items: list[Any] = []
    elif single:
        items = [value]
    elif place.source.blank(value):
        items = []
    elif isinstance(value, list | tuple):
        items = list(value)
    else:
        return place.wrong(place.source.expected_list(split(item_type)[0], names), value)
    label = next((m.template for m in meta if isinstance(m, Label)), None)
    entries = label is not None or entries_of(base)
    if place.required and not items and entries:
        place.source.empty(place)
    if label is None and place.source.names_items and entries:
        label = "'{key}' of {what}"
    out: list[Any] = []
    for i, item in enumerate(items):
        path = place.path if single else (*place.path, i)
        named = label.format(what=place.entry.what, key=place.key, n=i + 1) if label else None
        inner = Place(place.entry, place.key, path, named, item=True)
        found = _name(item, inner) if names else read_value(item_type, item, inner)
        if found is not MISSING:
            out.append(found)
    return out if typing.get_origin(base) is list else tuple(out)


def _fixed(types: tuple[Any, ...], value: Any, place: Place) -> Any:
    """``tuple[X, Y]``: so many items, each read as its own type."""
    if not isinstance(value, list | tuple) or len(value) != len(types):
        return place.wrong(f"a list of {len(types)}", value)
    out = []
    for i, (item_type, item) in enumerate(zip(types, value, strict=True)):
        inner = Place(place.entry, place.key, (*place.path, i), item=True)
        found = read_value(item_type, item, inner)
        if found is MISSING:
            return MISSING
        out.append(found)
    return tuple(out)


def _name(item: Any, place: Place) -> Any:
    if not isinstance(item, str) or not item.strip("/"):
        return place.wrong("a name", item)
    return item.strip("/")


def _mapping(base: Any, meta: tuple[Any, ...], value: Any, place: Place) -> Any:
    args = typing.get_args(base)
    value_type = args[1] if len(args) == 2 else Any
    named = next((m for m in meta if isinstance(m, Named)), None)
    if named is not None and place.source.blank(value):
        return {}
    if not isinstance(value, Mapping):
        if place.label is not None and place.source.names_items:
            place.source.not_mapping(place.label, place, place.path, place.line, value)
            return MISSING
        return place.wrong(place.source.expected_mapping(named is not None), value)
    if split(value_type)[0] is Any:
        return dict(value)
    out: dict[str, Any] = {}
    for key, item in value.items():
        label = named.label.format(name=key, what=place.entry.what) if named else None
        inner = Place(place.entry, place.key, (*place.path, str(key)), label)
        found = read_value(value_type, item, inner)
        if found is not MISSING:
            out[str(key)] = found
    return out


def _nested(cls: type, meta: tuple[Any, ...], value: Any, place: Place) -> Any:
    """A nested entry: a dataclass read from a mapping (for a :class:`Tagged` union, the
    dataclass its key names)."""
    label = next((m.template for m in meta if isinstance(m, Label)), "'{key}' of {what}")
    what = place.label or label.format(what=place.entry.what, key=place.key)
    in_named = place.label is not None and not place.item  # named by its key: its line
    line = place.source.key_line(place.path) if in_named else None
    name = str(place.path[-1]) if in_named else None
    entry = open_entry(value, place.source, place.path, what, place=place, line=line, name=name)
    if entry is None:
        return MISSING
    tagged = next((m for m in meta if isinstance(m, Tagged)), None)
    if tagged is not None:
        found = read_tagged(entry, tagged)
        return MISSING if found is None else found
    return read_entry(cls, entry, keep_unknown=has(meta, Open))


def read_tagged(entry: Entry, tagged: Tagged) -> Any:
    """An entry read as the dataclass its tag names; ``None`` if the tag names none
    (reported; its other keys then go unchecked)."""
    name = entry.read(tagged.key, typing.Annotated[str, NonEmpty(blank=True)], required=True)
    if name is MISSING:
        return None
    name = tagged.legacy.get(name, name)
    cls = tagged.resolve(name)
    if cls is None:
        choices = tagged.names()
        entry.error(
            tagged.key,
            tagged.unknown.format(
                noun=tagged.noun, value=name, what=entry.what,
                choices=", ".join(choices), hint=did_you_mean(name, choices),
            ),
        )  # fmt: skip
        return None
    found = read_entry(cls, entry)
    return None if found is MISSING else found


def read_inline(cls: type, entry: Entry, **given: Any) -> Any:
    """A dataclass read from some of an entry's keys (others are read apart), checked
    by its ``after_read``; :data:`MISSING` if it cannot be made (reported). Fields
    ``given`` are not read."""
    values = entry.read_fields(cls, **given)
    if values is None:
        return MISSING
    found = cls(**values)
    after = getattr(found, "after_read", None)
    if after is not None:
        found = after(entry)
    return MISSING if found is None else found


def read_entry(cls: type, entry: Entry, *, keep_unknown: bool = False, **given: Any) -> Any:
    """A dataclass read from an entry and checked by its ``after_read`` (which may rename
    the entry); :data:`MISSING` if it cannot be made (reported). Unknown keys are
    reported last, unless ``keep_unknown``. Fields ``given`` are not read."""
    found = read_inline(cls, entry, **given)
    if not keep_unknown:
        entry.close()
    return found


def read(schema: Any, value: Any, source: Source, what: str = "", **where: Any) -> Any:
    """A dataclass (or a :class:`Tagged` union of them) read from a mapping; ``None`` if
    it cannot be made, or, where the source is strict, if it has any problem (all are
    reported). ``where`` may give the ``path``, ``line`` and ``name`` of the mapping."""
    problems = source.problems
    entry = open_entry(value, source, what=what, **where)
    if entry is None:
        return None
    cls, meta = split(schema)
    tagged = next((m for m in meta if isinstance(m, Tagged)), None)
    found = read_tagged(entry, tagged) if tagged is not None else read_entry(cls, entry)
    if found is MISSING or (source.strict and source.problems > problems):
        return None
    return found
