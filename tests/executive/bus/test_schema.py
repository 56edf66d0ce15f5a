"""Typed payloads read JSON objects by their annotations and refuse bad input in one sentence."""

from __future__ import annotations

import dataclasses
import enum
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Annotated, Any

import pytest

from executive.bus.schema import Between, Payload, PayloadError, Text
from knowledge.record_class import record


class Color(enum.Enum):
    RED = "red"
    GREEN = "green"


@dataclass(frozen=True)
class Inner(Payload):
    name: Text


@dataclass(frozen=True)
class Sample(Payload):
    text: Text
    count: int = 0
    ratio: float | None = None
    flag: bool = False
    colors: list[Color] = field(default_factory=list)
    inner: Inner | None = None
    extra: dict[str, Any] = field(default_factory=dict)
    bounded: Annotated[int, Between(0, 10)] = 5


def test_a_full_payload_reads_back_to_what_it_was() -> None:
    sample = Sample("hi", 3, 0.5, True, [Color.RED], Inner("x"), {"a": [1]}, 7)
    assert Sample.from_payload(sample.to_payload()) == sample
    assert sample.to_payload()["colors"] == ["red"]


@record
class Declared(Payload):
    text: Text
    inner: Inner | None = None
    tags: tuple[str, ...] = ()


@dataclass(frozen=True)
class Written(Payload):
    text: Text
    inner: Inner | None = None
    tags: tuple[str, ...] = ()


def test_a_payload_class_compares_hashes_and_shows_as_a_frozen_dataclass_does() -> None:
    one, same, other = (
        Declared("a", Inner("x"), ("t",)),
        Declared("a", Inner("x"), ("t",)),
        Declared("b"),
    )
    assert one == same and hash(one) == hash(same) and len({one, same, other}) == 2
    assert one != other and one != Written("a", Inner("x"), ("t",)) and one != ("a",)
    assert repr(one) == repr(Written("a", Inner("x"), ("t",))).replace("Written", "Declared")
    assert repr(other) == "Declared(text='b', inner=None, tags=())"


@record
class Single(Payload):
    name: str


@record
class Bare(Payload):
    pass


def test_a_payload_class_of_one_field_or_none_compares_and_hashes_by_them() -> None:
    assert Single("a") == Single("a") and Single("a") != Single("b") and Single("a") != "a"
    assert hash(Single("a")) == hash(Single("a")) and len({Single("a"), Single("b")}) == 2
    assert Bare() == Bare() and hash(Bare()) == hash(Bare()) and Bare() != Single("a")
    assert (repr(Single("a")), repr(Bare())) == ("Single(name='a')", "Bare()")


def test_absent_fields_take_their_defaults_and_unknown_keys_are_ignored() -> None:
    assert Sample.from_payload({"text": "hi", "newer": 1}) == Sample("hi")


@pytest.mark.parametrize(
    ("payload", "message"),
    [
        ({}, "'text' must be a non-empty string, not null"),
        ({"text": "  "}, "'text' must be a non-empty string, not \"  \""),
        ({"text": "a", "count": "3"}, "'count' must be an integer, not \"3\""),
        ({"text": "a", "count": True}, "'count' must be an integer, not true"),
        ({"text": "a", "count": 10**30}, "'count' must be an integer, not 1000000000000"),
        ({"text": "a", "ratio": float("nan")}, "'ratio' must be a finite number, not NaN"),
        ({"text": "a", "ratio": float("inf")}, "'ratio' must be a finite number"),
        ({"text": "a", "flag": 1}, "'flag' must be true or false, not 1"),
        ({"text": "a", "colors": "red"}, "'colors' must be a list, not \"red\""),
        ({"text": "a", "colors": ["blue"]}, "'colors[0]' must be one of red, green, not \"blue\""),
        ({"text": "a", "inner": {}}, "'inner.name' must be a non-empty string, not null"),
        ({"text": "a", "extra": [1]}, "'extra' must be an object, not [1]"),
        ({"text": "a", "bounded": 11}, "'bounded' must be from 0 to 10, not 11"),
    ],
)
def test_a_bad_payload_is_refused_with_the_field_and_the_value(
    payload: dict[str, Any], message: str
) -> None:
    with pytest.raises(PayloadError) as raised:
        Sample.from_payload(payload)
    assert message in str(raised.value)


# --- records in payloads -----------------------------------------------------------------


@dataclass(frozen=True)
class Point:
    """A record: a frozen dataclass, not a payload."""

    name: str
    at: tuple[float, float]
    value: bool | float = True
    tags: Mapping[str, int] = field(default_factory=dict)
    note: str | None = None
    label: str = field(init=False, compare=False)

    def __post_init__(self) -> None:
        object.__setattr__(self, "label", f"{self.name}@{self.at[0]:g},{self.at[1]:g}")


@record
class Carrying(Payload):
    point: Point
    points: list[Point] = field(default_factory=list)
    either: list[Point] | Inner | None = None


def test_a_record_in_a_payload_is_written_whole_and_read_back() -> None:
    carrying = Carrying(Point("a", (1.0, 2.0), 3.0, {"x": 1}), [Point("b", (0.0, 0.0))])
    written = carrying.to_payload()
    # every field of a record is written, None too, and what it derives (init=False)
    assert written["point"] == {"name": "a", "at": [1.0, 2.0], "value": 3.0, "tags": {"x": 1},
                                "note": None, "label": "a@1,2"}  # fmt: skip
    assert "either" not in written  # a payload's optional field left at None is not sent
    read_back = Carrying.from_payload(written)
    assert read_back == carrying and read_back.point.label == "a@1,2"
    assert read_back.points[0].value is True  # true is a bool, not the number 1


def test_a_union_reads_the_first_option_that_fits() -> None:
    point = {"name": "a", "at": [1, 2]}
    assert Carrying.from_payload({"point": point, "either": [point]}).either == [
        Point("a", (1.0, 2.0))
    ]
    assert Carrying.from_payload({"point": point, "either": {"name": "x"}}).either == Inner("x")


@pytest.mark.parametrize(
    ("point", "message"),
    [
        ({"name": "a", "at": [1.0]}, "'point.at' must be a list of 2, not [1.0]"),
        ({"name": "a", "at": [1, 2], "value": "high"}, "'point.value' must be true or false"),
        ({"name": "a", "at": [1, 2], "tags": {"x": "1"}}, "'point.tags.x' must be an integer"),
        ({"at": [1, 2]}, "'point.name' must be a string, not null"),
        ("a", "'point' must be an object, not \"a\""),
    ],
)
def test_a_bad_record_is_refused_with_the_field_and_the_value(point: Any, message: str) -> None:
    with pytest.raises(PayloadError) as raised:
        Carrying.from_payload({"point": point})
    assert message in str(raised.value)


def test_a_payload_class_is_frozen_as_a_frozen_dataclass_is() -> None:
    declared = Declared("a")
    with pytest.raises(dataclasses.FrozenInstanceError):
        declared.text = "b"  # type: ignore[misc]
    with pytest.raises(dataclasses.FrozenInstanceError):
        del declared.text  # type: ignore[misc]
    assert dataclasses.replace(declared, text="b") == Declared("b")
    assert Declared(text="a", tags=("t",)).tags == ("t",)
    with pytest.raises(TypeError, match="missing the argument 'text'"):
        Declared()  # type: ignore[call-arg]


@dataclass(frozen=True)
class Record:
    """A knowledge record, as the knowledge base gives it: not a payload."""

    name: str
    state: Color
    value: bool | float = False
    note: str | None = None


@record
class Records(Payload):
    records: tuple[Record, ...]
    by_name: Mapping[str, Record] = field(default_factory=dict)
    inner: list[Inner] = field(default_factory=list)
    extra: Any = None


def test_a_payload_reads_nested_records_and_sends_them_back() -> None:
    sent = Records(
        (Record("a", Color.RED, 0.5), Record("b", Color.GREEN, True, "n")),
        {"c": Record("c", Color.RED)},
        [Inner("x")],
        {"free": [1]},
    )
    assert Records.from_payload(sent.to_payload()) == sent
    assert sent.to_payload()["records"][0] == {
        "name": "a", "state": "red", "value": 0.5, "note": None
    }  # fmt: skip


@pytest.mark.parametrize(
    ("payload", "message"),
    [
        ({"records": [{"name": "a"}]}, "'records[0].state' must be one of red, green, not null"),
        (
            {"records": [{"name": "a", "state": "red", "value": "x"}]},
            "'records[0].value' must be true or false or a number, not \"x\"",
        ),
        ({"records": [], "by_name": {"c": 1}}, "'by_name.c' must be an object, not 1"),
        ({"records": [], "inner": [{"name": ""}]}, "'inner[0].name' must be a non-empty string"),
    ],
)
def test_a_bad_nested_record_is_refused_with_its_place(
    payload: dict[str, Any], message: str
) -> None:
    with pytest.raises(PayloadError) as raised:
        Records.from_payload(payload)
    assert message in str(raised.value)
