"""One reader reads annotated frozen dataclasses from plain configurations and from YAML,
naming the place and the reason of every problem."""

from __future__ import annotations

import enum
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Annotated, Any

import pytest

from knowledge.conventions import (
    AtLeast,
    EntryLine,
    FromKey,
    Inside,
    Key,
    KeyLines,
    Label,
    Named,
    Names,
    NonEmpty,
    OneOf,
    OneOrMore,
    Required,
    Titles,
    When,
)
from knowledge.finding import Report
from knowledge.typed_reader import Entry, Source, read
from knowledge.yamlsource import DocumentSource, read_file


class Colour(enum.Enum):
    RED = "red"
    GREEN = "green"


@dataclass(frozen=True)
class Lamp:
    """A lamp of a mast, named by its key."""

    name: Annotated[str, FromKey()]
    colour: Colour = Colour.RED
    line: Annotated[int, EntryLine()] = 0


@dataclass(frozen=True, kw_only=True)
class Mast:
    """A schema with most conventions: bounds, choices, names, entries by name, a key
    only some entries have, an older spelling."""

    name: Annotated[str, NonEmpty(), Titles("mast '{value}'")]
    height: Annotated[float, AtLeast(1.0)] = 2.0
    kind: Annotated[str, OneOf(("steel", "wood"), "mast kind")] = "steel"
    grain: Annotated[str | None, Required(), When("kind", "wood")] = None
    damping: Annotated[float, Inside(0.0, 1.0), Key("damping", "dampning")] = 0.5
    crew: Annotated[tuple[str, ...], Names()] = ()
    tags: Annotated[tuple[str, ...], OneOrMore()] = ()
    lamps: Annotated[Mapping[str, Lamp], Named("lamp '{name}' of {what}")] = field(
        default_factory=dict
    )
    lines: Annotated[Mapping[str, int], KeyLines()] = field(default_factory=dict, compare=False)

    def after_read(self, entry: Entry) -> Mast | None:
        if "top" in self.lamps and self.height < 3:
            entry.error("height", f"{entry.what}: a top lamp needs a height of 3")
            return None
        return self


@dataclass(frozen=True)
class Harbour:
    masts: Annotated[tuple[Mast, ...], Label("mast {n} of {what}")] = ()


def problems(value: object, schema: Any = Mast) -> tuple[object, list[str]]:
    report = Report("config")
    found = read(schema, value, Source(report), "the mast")
    return found, [f.message for f in report.findings]


def test_a_valid_entry_reads_into_its_dataclass_with_defaults() -> None:
    found, messages = problems(
        {"name": "a", "crew": ["/ann", "bo"], "tags": "tall", "lamps": {"top": {}}, "height": 4}
    )
    assert messages == []
    assert found == Mast(
        name="a", height=4.0, crew=("ann", "bo"), tags=("tall",), lamps={"top": Lamp("top")}
    )


@pytest.mark.parametrize(
    ("value", "message"),
    [
        ({}, "the mast has no 'name'"),
        ({"name": ""}, "'name' of the mast must be a non-empty string, not ''"),
        ({"name": "a", "height": 0.5}, "'height' of mast 'a' must be at least 1, not 0.5"),
        ({"name": "a", "height": "x"}, "'height' of mast 'a' must be a number, not 'x'"),
        (
            {"name": "a", "damping": 1},
            "'damping' of mast 'a' must be between 0 and 1 (exclusive), not 1",
        ),
        (
            {"name": "a", "kind": "stele"},
            "unknown mast kind 'stele' in mast 'a' (choose from steel, wood) "
            "(did you mean 'steel'?)",
        ),
        ({"name": "a", "kind": "wood"}, "mast 'a' has no 'grain'"),
        ({"name": "a", "grain": "oak"}, "unknown key 'grain' in mast 'a'"),
        ({"name": "a", "hieght": 3}, "unknown key 'hieght' in mast 'a' (did you mean 'height'?)"),
        ({"name": "a", "crew": ["/"]}, "'crew' of mast 'a' must list names, not '/'"),
        ({"name": "a", "tags": 3}, "'tags' of mast 'a' must be a list of strings, not 3"),
        (
            {"name": "a", "damping": 0.1, "dampning": 0.2},
            "mast 'a' has both 'damping' and 'dampning'",
        ),
        ({"name": "a", "lamps": {"top": 3}}, "lamp 'top' of mast 'a' must be a mapping, not 3"),
        (
            {"name": "a", "lamps": {"top": {"colour": "blue"}}},
            "'colour' of lamp 'top' of mast 'a' must be one of red, green, not 'blue'",
        ),
        ({"name": "a", "lamps": {"top": {}}}, "mast 'a': a top lamp needs a height of 3"),
        ("mast", "the mast must be a mapping, not 'mast'"),
    ],
)
def test_a_wrong_entry_is_reported_in_one_sentence_and_not_read(
    value: object, message: str
) -> None:
    found, messages = problems(value)
    assert found is None
    assert message in messages, messages


def test_an_older_spelling_is_read_like_the_key() -> None:
    found, messages = problems({"name": "a", "dampning": 0.25})
    assert messages == [] and isinstance(found, Mast) and found.damping == 0.25


def test_the_items_of_a_list_of_entries_are_named_by_their_number() -> None:
    _, messages = problems({"masts": [{"name": "a"}, {"height": 2}]}, Harbour)
    assert messages == ["mast 2 of the mast has no 'name'"]


YAML = """\
masts:
  - name: north
    height: 0.5
    crew: [ann]
    tags: 12
    lamps:
      top:
        colour: blue
  - name: 7
    kind: wood
    grain: ~
    crwe: [bo]
"""


def test_a_yaml_document_is_read_with_the_line_of_every_problem(tmp_path: Path) -> None:
    path = tmp_path / "harbour.yaml"
    path.write_text(YAML)
    report = Report(str(path))
    document = read_file(path, report)
    assert document is not None
    read(Harbour, document.value, DocumentSource(document, report), "the harbour")
    assert [(f.line, f.message) for f in report.findings] == [
        (3, "'height' of mast 'north' must be at least 1, not 0.5"),
        (5, "'tags' of mast 'north' must be a list of strings, not '12'"),
        (8, "'colour' of lamp 'top' of mast 'north' must be one of red, green, not 'blue'"),
        (3, "mast 'north': a top lamp needs a height of 3"),  # the default height: 2
        (11, "'grain' of mast '7' must be a string, not '~'"),  # a number is a name; null no text
        (12, "unknown key 'crwe' in mast '7' (did you mean 'crew'?)"),
    ]


def test_the_entries_of_a_yaml_document_know_their_lines(tmp_path: Path) -> None:
    path = tmp_path / "harbour.yaml"
    path.write_text("masts:\n  - name: a\n    height: 4\n    lamps:\n      top: {}\n")
    report = Report(str(path))
    document = read_file(path, report)
    assert document is not None
    found = read(Harbour, document.value, DocumentSource(document, report), "the harbour")
    assert report.findings == [] and found is not None
    (mast,) = found.masts
    assert mast.lines == {"name": 2, "height": 3, "lamps": 4}
    assert mast.lamps["top"].line == 5
