"""Where values come from and where each one is: the wording of a problem, and its line.

A :class:`Source` stands for one input: a plain configuration (an observer entry, with
the lines its robot description gave, or none), a YAML document
(:class:`knowledge.yamlsource.DocumentSource`) or a bus payload
(:class:`executive.bus.schema.PayloadSource`). It says where problems go (a report,
with the line of each place; or an exception at the first), how a value shows in a
message, whether a null is an absent value, and whether an unknown key is a problem
(reported with a did-you-mean) or ignored. A :class:`Place` is where one value is, for
the messages about it; :mod:`knowledge.typed_reader` reads values by both.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

from knowledge.errors import did_you_mean
from knowledge.field_plan import MISSING, PathPart, dotted, entries_of

if TYPE_CHECKING:
    from knowledge.finding import Report
    from knowledge.typed_reader import Entry

LineOf = Callable[[str], int | None]


class Source:
    """Where values come from (a plain configuration, with or without lines).

    Args:
        report: where problems go.
        line_of: the line of a dotted path (of its nearest enclosing key if unknown).
        folder: where relative paths start.
        context: what the checks of a schema may need (e.g. the robot, for its names).
    """

    null_is_absent = True
    report_unknown = True
    strict = True  # what has a problem is not read (else: defaults stand in, see read)
    strict_numbers = False  # numbers of JSON: finite, and integers within 64 bits
    names_items = True  # messages name the items of a list ("state 2 of ...")

    def __init__(
        self,
        report: Report | None = None,
        line_of: LineOf | None = None,
        *,
        folder: Path | None = None,
        context: Any = None,
    ) -> None:
        self.report = report
        self.line_of = line_of
        self.folder = folder
        self.context = context
        self.problems = 0  # how many were reported

    # --- places --------------------------------------------------------------------------

    def key_line(self, path: Sequence[PathPart]) -> int | None:
        """The line of the key (or list item) at ``path``."""
        return self.line_of(dotted(path)) if self.line_of is not None else None

    def value_line(self, path: Sequence[PathPart]) -> int | None:
        """The line where the value at ``path`` starts."""
        return self.key_line(path)

    def first_that_reads(self, reads: Sequence[Callable[[], Any]]) -> Any:
        """The value of the first of ``reads`` (an option of a union each, in order, of
        those the value fits) that reads it. A source that reports its problems reads
        the first: trying another would report the first one's problems too."""
        return reads[0]()

    # --- values in messages --------------------------------------------------------------

    def text(self, value: Any, path: Sequence[PathPart]) -> str | None:
        """A scalar that is not a string as a text, if the source reads it so (YAML)."""
        return None

    def blank(self, value: Any) -> bool:
        """Whether a value written for entries (a list, a mapping of names) means none."""
        return value is None and not self.null_is_absent

    def describe(self, value: Any, path: Sequence[PathPart]) -> str:
        """How a value reads in a message."""
        if value is None:
            return "empty"
        if isinstance(value, bool):
            return "true" if value else "false"
        if isinstance(value, str | int | float):
            return repr(value)
        if isinstance(value, Mapping):
            return "a mapping"
        if isinstance(value, list | tuple):
            return "a list"
        return type(value).__name__

    def describe_number(self, raw: Any, value: float, path: Sequence[PathPart]) -> str:
        """How a number out of its bounds reads in a message."""
        return self.describe(raw, path)

    # --- problems ------------------------------------------------------------------------

    def error(self, line: int | None, message: str) -> None:
        self.problems += 1
        if self.report is not None:
            self.report.error(line, message)

    def subject(self, place: Place) -> str:
        """How a message names a value: ``'window_size' of the filter of ...``."""
        if place.label is not None:
            return place.label
        return f"'{place.key}' of {place.entry.what}"

    def wrong(self, place: Place, expected: str, value: Any) -> Any:
        """Report a value that is not ``expected``; returns :data:`MISSING`."""
        if place.item and place.label is None:  # an item of a list of scalars
            message = f"'{place.key}' of {place.entry.what} must list {_plural(expected)}"
        else:
            message = f"{self.subject(place)} must be {expected}"
        shown = self.describe(value, place.path)
        self.error(self.value_line(place.path), f"{message}, not {shown}")
        return MISSING

    def out_of_bounds(self, place: Place, bound: object, raw: Any, value: float) -> Any:
        shown = self.describe_number(raw, value, place.path)
        self.error(
            self.value_line(place.path), f"{self.subject(place)} must be {bound}, not {shown}"
        )
        return MISSING

    def not_mapping(
        self, what: str, place: Place | None, path: Sequence[PathPart], line: int | None, value: Any
    ) -> None:
        """Report an entry that is no mapping."""
        self.error(line, f"{what} must be a mapping, not {self.describe(value, path)}")

    def missing(self, entry: Entry, key: str, annotation: Any) -> Any:
        """Report an absent value; returns the value to use (:data:`MISSING`: none)."""
        suffix = " (a list)" if entries_of(annotation) else ""
        entry.source.error(entry.line, f"{entry.what} has no '{key}'{suffix}")
        return MISSING

    def empty(self, place: Place) -> None:
        """Report a required list of entries that is empty."""
        place.entry.error(place.key, f"{place.entry.what} has no '{place.key}' (a list)")

    def unknown(self, entry: Entry, key: str, known: list[str]) -> None:
        """Report a key no field of the entry has."""
        hint = did_you_mean(key, sorted(known))
        self.error(entry.key_line(key), f"unknown key '{key}' in {entry.what}{hint}")

    def expected_list(self, item: Any, names: bool) -> str:
        if names:
            return "a list of names"
        return "a list of strings" if item in (str, Path) else "a list"

    def expected_mapping(self, named: bool) -> str:
        return "a mapping of names to entries" if named else "a mapping"


_PLURALS = {"a string": "strings", "a non-empty string": "strings", "a name": "names"}


def _plural(expected: str) -> str:
    return _PLURALS.get(expected, expected)


class Place:
    """Where a value is: in ``entry``, under its ``key``, at ``path``.

    ``label`` names a value that is an item of a list or of a mapping of names (``state
    2 of ...``, ``task 'move_to'``); ``item`` says it is an item of a list.
    """

    __slots__ = ("entry", "item", "key", "label", "path", "required")

    def __init__(
        self,
        entry: Entry,
        key: str,
        path: tuple[PathPart, ...],
        label: str | None = None,
        *,
        item: bool = False,
        required: bool = False,
    ) -> None:
        self.entry = entry
        self.key = key
        self.path = path
        self.label = label
        self.item = item
        self.required = required

    @property
    def source(self) -> Source:
        return self.entry.source

    @property
    def line(self) -> int | None:
        return self.source.value_line(self.path)

    def wrong(self, expected: str, value: Any) -> Any:
        """Report that the value is not ``expected``; returns :data:`MISSING`."""
        return self.source.wrong(self, expected, value)

    def error(self, message: str, *, at_key: bool = False) -> Any:
        """Report a problem at the value's line (or its key's); returns :data:`MISSING`."""
        line = self.source.key_line(self.path) if at_key else self.line
        self.source.error(line if line is not None else self.entry.line, message)
        return MISSING
