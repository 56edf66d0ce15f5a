"""Read an observer configuration (a plain mapping) against a schema, with lines.

Observer entries reach the monitoring as plain mappings: from a robot description
(an :class:`~knowledge.description.ObserverSpec`, which knows the line of every
nested key), from a standalone observers file, or from a bus request (no lines at
all). :class:`Entry` reads one mapping key by key with typed accessors, reports each
problem once as ``file:line: message``, and at :meth:`Entry.close` reports every key
no accessor asked for as unknown, with a did-you-mean.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any

from knowledge.finding import Report
from knowledge.yamlsource import did_you_mean

LineOf = Callable[[str], int | None]


def no_lines(path: str) -> int | None:
    """The line lookup of a configuration that came without lines (a bus request)."""
    return None


@dataclass(frozen=True)
class Source:
    """Where an observer configuration came from: the report and the line of each path."""

    report: Report
    line_of: LineOf = no_lines


def describe(value: object) -> str:
    """How a value reads in an error message."""
    if value is None:
        return "empty"
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, (str, int, float)):
        return repr(value)
    if isinstance(value, Mapping):
        return "a mapping"
    if isinstance(value, (list, tuple)):
        return "a list"
    return type(value).__name__


def _is_number(value: object) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool)


class Entry:
    """One mapping of an observer configuration, read against a schema.

    Args:
        value: the mapping as written.
        source: the report to add problems to and the line lookup.
        where: the dotted path of the mapping inside the observer entry ("" for the entry).
        what: how messages name the mapping, e.g. ``topic 'scan' of the frequency observer``.
    """

    def __init__(self, value: object, source: Source, where: str, what: str) -> None:
        self.source = source
        self.where = where
        self.what = what
        self.valid = isinstance(value, Mapping)
        self._values: dict[str, Any] = (
            {str(k): v for k, v in value.items()} if isinstance(value, Mapping) else {}
        )
        self._read: set[str] = set()
        if not self.valid:
            self.error(None, f"{what} must be a mapping, not {describe(value)}")

    # --- places and problems --------------------------------------------------------

    def path(self, key: str | int | None) -> str:
        if key is None:
            return self.where
        return f"{self.where}.{key}" if self.where else str(key)

    def line(self, key: str | int | None = None) -> int | None:
        return self.source.line_of(self.path(key))

    def error(self, key: str | int | None, message: str) -> None:
        self.source.report.error(self.line(key), message)

    def _wrong(self, key: str, value: object, expected: str) -> None:
        self.error(key, f"'{key}' of {self.what} must be {expected}, not {describe(value)}")

    def _missing(self, key: str) -> None:
        self.error(None, f"{self.what} has no '{key}'")

    # --- access ---------------------------------------------------------------------

    def has(self, key: str) -> bool:
        return key in self._values

    def get(self, key: str) -> Any:
        """The raw value of a key (marks it as read); ``None`` if absent."""
        self._read.add(key)
        return self._values.get(key)

    def text(self, key: str, default: str | None = None, *, required: bool = False) -> str | None:
        value = self.get(key)
        if value is None:
            if required:
                self._missing(key)
            return default
        if not isinstance(value, str) or not value:
            self._wrong(key, value, "a non-empty string")
            return default
        return value

    def number(
        self,
        key: str,
        default: float | None = None,
        *,
        required: bool = False,
        minimum: float | None = None,
        above: float | None = None,
        below: float | None = None,
    ) -> float | None:
        """A number; ``minimum`` is inclusive, ``above`` and ``below`` are exclusive."""
        value = self.get(key)
        if value is None:
            if required:
                self._missing(key)
            return default
        if not _is_number(value):
            self._wrong(key, value, "a number")
            return default
        number = float(value)
        if minimum is not None and number < minimum:
            self._wrong(key, value, f"at least {minimum:g}")
            return default
        if above is not None and below is not None and not above < number < below:
            self._wrong(key, value, f"between {above:g} and {below:g} (exclusive)")
            return default
        if above is not None and number <= above:
            self._wrong(key, value, f"greater than {above:g}")
            return default
        if below is not None and number >= below:
            self._wrong(key, value, f"less than {below:g}")
            return default
        return number

    def integer(
        self,
        key: str,
        default: int | None = None,
        *,
        required: bool = False,
        minimum: int | None = None,
    ) -> int | None:
        value = self.get(key)
        if value is None:
            if required:
                self._missing(key)
            return default
        if not isinstance(value, int) or isinstance(value, bool):
            self._wrong(key, value, "an integer")
            return default
        if minimum is not None and value < minimum:
            self._wrong(key, value, f"at least {minimum}")
            return default
        return value

    def flag(self, key: str, default: bool) -> bool:
        value = self.get(key)
        if value is None:
            return default
        if not isinstance(value, bool):
            self._wrong(key, value, "true or false")
            return default
        return value

    def names(self, key: str) -> tuple[str, ...]:
        """A list of names; a single name is a list of one; leading '/' (ROS) is dropped."""
        value = self.get(key)
        if value is None:
            return ()
        items = [value] if isinstance(value, str) else value
        if not isinstance(items, list):
            self._wrong(key, value, "a list of names")
            return ()
        out: list[str] = []
        for i, item in enumerate(items):
            if not isinstance(item, str) or not item.strip("/"):
                self.error(
                    f"{key}.{i}" if isinstance(value, list) else key,
                    f"'{key}' of {self.what} must list names, not {describe(item)}",
                )
            else:
                out.append(item.strip("/"))
        return tuple(out)

    def entry(self, key: str, what: str, *, required: bool = False) -> Entry | None:
        """A nested mapping."""
        value = self.get(key)
        if value is None:
            if required:
                self._missing(key)
            return None
        return Entry(value, self.source, self.path(key), what)

    def items(self, key: str, *, required: bool = False) -> list[tuple[str, object]]:
        """The items of a list as (dotted path, value); a non-list is reported."""
        value = self.get(key)
        if value is None or value == []:
            if required:
                self.error(key if value == [] else None, f"{self.what} has no '{key}' (a list)")
            return []
        if not isinstance(value, list):
            self._wrong(key, value, "a list")
            return []
        return [(self.path(f"{key}.{i}"), item) for i, item in enumerate(value)]

    def entries(self, key: str, what: str, *, required: bool = False) -> list[Entry]:
        """A list of mappings; ``what`` names each, ``{n}`` becomes its 1-based number."""
        return [
            Entry(item, self.source, where, what.replace("{n}", str(i + 1)))
            for i, (where, item) in enumerate(self.items(key, required=required))
        ]

    # --- end ------------------------------------------------------------------------

    def close(self) -> None:
        """Report every key no accessor read as unknown, with a did-you-mean."""
        for key in self._values:
            if key not in self._read:
                hint = did_you_mean(key, sorted(self._read))
                self.error(key, f"unknown key '{key}' in {self.what}{hint}")
