"""The ``Annotated`` metadata of schemas: constraints and conventions the reader honours.

A schema field says more than its type with metadata, e.g.
``window_size: Annotated[int | None, AtLeast(2)] = None`` or
``functionalities: Annotated[Mapping[str, FunctionalitySpec], Named("functionality
'{name}'")]``. :mod:`knowledge.typed_reader` reads values by them.
"""

from __future__ import annotations

import os
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from knowledge.typed_reader import Place


class Marker:
    """A piece of metadata: a plain class, compared and shown by its slots (not a
    dataclass: a command that only reads bus payloads imports this module too, and
    making a dataclass costs half a millisecond)."""

    __slots__: tuple[str, ...] = ()

    def __init__(self, **values: Any) -> None:
        for name, value in values.items():
            object.__setattr__(self, name, value)

    def _values(self) -> tuple[Any, ...]:
        return tuple(getattr(self, name) for name in self.__slots__)

    def __eq__(self, other: object) -> bool:
        return (
            isinstance(other, Marker)
            and type(other) is type(self)
            and self._values() == other._values()
        )

    def __hash__(self) -> int:
        return hash((type(self), self._values()))

    def __repr__(self) -> str:
        return f"{type(self).__name__}({', '.join(map(repr, self._values()))})"

    def __setattr__(self, name: str, value: Any) -> None:
        raise AttributeError(f"{type(self).__name__} is immutable")


# --- bounds of numbers -------------------------------------------------------------------


class AtLeast(Marker):
    """A number of at least ``low``."""

    __slots__ = ("low",)
    low: float

    def __init__(self, low: float) -> None:
        super().__init__(low=low)

    def holds(self, value: float) -> bool:
        return value >= self.low

    def __str__(self) -> str:
        return f"at least {self.low:g}"


class AtMost(Marker):
    """A number of at most ``high``."""

    __slots__ = ("high",)
    high: float

    def __init__(self, high: float) -> None:
        super().__init__(high=high)

    def holds(self, value: float) -> bool:
        return value <= self.high

    def __str__(self) -> str:
        return f"at most {self.high:g}"


class Above(Marker):
    """A number greater than ``low``."""

    __slots__ = ("low",)
    low: float

    def __init__(self, low: float) -> None:
        super().__init__(low=low)

    def holds(self, value: float) -> bool:
        return value > self.low

    def __str__(self) -> str:
        return f"greater than {self.low:g}"


class Below(Marker):
    """A number less than ``high``."""

    __slots__ = ("high",)
    high: float

    def __init__(self, high: float) -> None:
        super().__init__(high=high)

    def holds(self, value: float) -> bool:
        return value < self.high

    def __str__(self) -> str:
        return f"less than {self.high:g}"


class Inside(Marker):
    """A number between ``low`` and ``high``, both excluded."""

    __slots__ = ("high", "low")
    low: float
    high: float

    def __init__(self, low: float, high: float) -> None:
        super().__init__(low=low, high=high)

    def holds(self, value: float) -> bool:
        return self.low < value < self.high

    def __str__(self) -> str:
        return f"between {self.low:g} and {self.high:g} (exclusive)"


class Between(Marker):
    """A number from ``low`` to ``high``, both included."""

    __slots__ = ("high", "low")
    low: float
    high: float

    def __init__(self, low: float, high: float) -> None:
        super().__init__(low=low, high=high)

    def holds(self, value: float) -> bool:
        return self.low <= value <= self.high

    def __str__(self) -> str:
        return f"from {self.low:g} to {self.high:g}"


Bound = AtLeast | AtMost | Above | Below | Inside | Between


# --- other constraints -------------------------------------------------------------------


class NonEmpty(Marker):
    """A text with something in it (not only blanks, unless ``blank``), or a list with
    an item."""

    __slots__ = ("blank",)
    blank: bool

    def __init__(self, *, blank: bool = False) -> None:
        super().__init__(blank=blank)


class OneOf(Marker):
    """A text that is one of ``choices``; messages call it a ``noun`` (``filter type``)."""

    __slots__ = ("choices", "noun")
    choices: tuple[str, ...]
    noun: str

    def __init__(self, choices: tuple[str, ...], noun: str) -> None:
        super().__init__(choices=choices, noun=noun)


class Exists(Marker):
    """A path that names an existing file (else: ``'key' names no file: ...``)."""

    __slots__ = ()

    @staticmethod
    def missing(key: str, value: object, found: Path, folder: Path | None) -> str:
        """Why ``value`` (``found`` once resolved) names no file, and, for a path that
        leaves its file's folder (a file copied without what it names, ``cp -r
        examples/usecase myrobot``), what to do."""
        said = f"'{key}' names no file: {value}"
        if not str(value).startswith(".."):
            return said
        name = Path(str(value)).name
        return (
            f"{said} (that is {os.path.normpath(found)}); copied from elsewhere? copy {name}"
            f" into {os.path.normpath(folder or found.parent)} and write '{key}: {name}'"
        )


class Check(Marker):
    """``function(value, place)`` checks a value once it is read: it returns the value
    to keep, or :data:`~knowledge.typed_reader.MISSING` (having reported why at
    ``place``)."""

    __slots__ = ("function",)
    function: Callable[[Any, Place], Any]

    def __init__(self, function: Callable[[Any, Place], Any]) -> None:
        super().__init__(function=function)


class Convert(Marker):
    """``function(value, place)`` reads a value as written, instead of its annotation:
    it returns the value, or :data:`~knowledge.typed_reader.MISSING` (reported)."""

    __slots__ = ("function",)
    function: Callable[[Any, Place], Any]

    def __init__(self, function: Callable[[Any, Place], Any]) -> None:
        super().__init__(function=function)


# --- conventions of documents ------------------------------------------------------------


class Key(Marker):
    """The key a document writes for a field, when it is not the field's name; ``old``
    are older spellings, accepted too (but not together with it)."""

    __slots__ = ("name", "old")
    name: str
    old: tuple[str, ...]

    def __init__(self, name: str, *old: str) -> None:
        super().__init__(name=name, old=old)


class Required(Marker):
    """An absent value is a problem, although the field has a default (used then)."""

    __slots__ = ()


class Default(Marker):
    """The value an absent (or wrong) key gives a field, when it is not the constructor's
    default or the constructor has none (e.g. ``None``, for ``after_read`` to fill in
    from other fields)."""

    __slots__ = ("value",)
    value: Any

    def __init__(self, value: Any) -> None:
        super().__init__(value=value)


class OrDefault(Marker):
    """An empty text stands for the field's default."""

    __slots__ = ()


class Nullable(Marker):
    """A null in a YAML document means ``None`` (else it is a wrong value there)."""

    __slots__ = ()


class OneOrMore(Marker):
    """A single value is accepted as a list of one."""

    __slots__ = ()


class Names(Marker):
    """A list of names (a single name is a list of one) of which a leading ``/`` (ROS)
    is dropped."""

    __slots__ = ()


class Named(Marker):
    """A mapping of names to entries; ``label`` names each in messages (``{name}``; and
    ``{what}``, the enclosing entry), e.g. ``task '{name}'``."""

    __slots__ = ("label",)
    label: str

    def __init__(self, label: str) -> None:
        super().__init__(label=label)


class Label(Marker):
    """How messages name a nested entry (each, for a list): ``{what}`` is the enclosing
    entry's name, ``{key}`` the key, ``{n}`` the 1-based number of a list item.
    Without it, ``'{key}' of {what}``."""

    __slots__ = ("template",)
    template: str

    def __init__(self, template: str) -> None:
        super().__init__(template=template)


class Titles(Marker):
    """This field names its entry, once read: ``{value}`` is its value, ``{owner}`` the
    name of the enclosing entry, other names are fields read before. The first field
    that names the entry does (an absent or empty one does not); from the field
    ``after`` on, if one is given."""

    __slots__ = ("after", "template")
    template: str
    after: str | None

    def __init__(self, template: str, *, after: str | None = None) -> None:
        super().__init__(template=template, after=after)


class When(Marker):
    """The key belongs to an entry only when its field ``field`` holds one of
    ``values`` (else it is an unknown key)."""

    __slots__ = ("field", "values")
    field: str
    values: tuple[Any, ...]

    def __init__(self, field: str, *values: Any) -> None:
        super().__init__(field=field, values=values)


class Open(Marker):
    """Entries that keep keys of their own: unknown keys are not problems."""

    __slots__ = ()


class Tagged(Marker):
    """A union of entries told apart by the text under ``key``: ``types`` maps a name to
    a dataclass, or is a function from a name to one (or ``None``); ``legacy`` maps old
    names to new ones; ``choices`` lists the names for messages (default: ``types``).
    ``unknown`` is the message for a name that is none of them (``{noun}``, ``{value}``,
    ``{what}``, ``{choices}``, and ``{hint}``: a did-you-mean)."""

    __slots__ = ("choices", "key", "legacy", "noun", "types", "unknown")
    key: str
    noun: str
    types: Mapping[str, type] | Callable[[str], type | None]
    choices: Sequence[str] | Callable[[], Sequence[str]]
    legacy: Mapping[str, str]
    unknown: str

    def __init__(
        self,
        key: str,
        noun: str,
        types: Mapping[str, type] | Callable[[str], type | None],
        *,
        choices: Sequence[str] | Callable[[], Sequence[str]] = (),
        legacy: Mapping[str, str] | None = None,
        unknown: str = "unknown {noun} '{value}' in {what} (choose from {choices}){hint}",
    ) -> None:
        super().__init__(
            key=key, noun=noun, types=types, choices=choices, legacy=legacy or {}, unknown=unknown
        )

    def resolve(self, name: str) -> type | None:
        """The dataclass a (canonical) name stands for."""
        if callable(self.types):
            return self.types(name)
        return self.types.get(name)

    def names(self) -> list[str]:
        if callable(self.choices):
            return list(self.choices())
        return list(self.choices or self.types)  # type: ignore[arg-type]


# --- fields filled from the entry --------------------------------------------------------


class FromKey(Marker):
    """The field holds the entry's name in a :class:`Named` mapping."""

    __slots__ = ()


class EntryLine(Marker):
    """The field holds the line of the entry."""

    __slots__ = ()


class KeyLines(Marker):
    """The field holds the line of each key written, and of the keys of the mappings
    under ``nested`` (as ``key.inner``)."""

    __slots__ = ("nested",)
    nested: tuple[str, ...]

    def __init__(self, *nested: str) -> None:
        super().__init__(nested=nested)


class AllLines(Marker):
    """The field holds the line of every key and list item below the entry, by dotted
    path (``topics.0.filter.window_size``)."""

    __slots__ = ()


class Whole(Marker):
    """The field holds the entry's mapping as written."""

    __slots__ = ()
