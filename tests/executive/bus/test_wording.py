"""Counts, numbers and values read the same in every view."""

from __future__ import annotations

from executive.bus.wording import number, pairs, plural, seconds, value


def test_a_count_of_one_is_singular_and_others_plural() -> None:
    assert [plural(n, "fault") for n in (0, 1, 2)] == ["0 faults", "1 fault", "2 faults"]
    assert plural(2, "diagnosis", "diagnoses") == "2 diagnoses"


def test_numbers_are_rounded_without_trailing_zeros() -> None:
    assert [number(v) for v in (4.0, 0.997928, 0.05962, 179.79, -0.001, 7)] == [
        "4", "1", "0.06", "179.79", "0", "7"
    ]  # fmt: skip
    assert seconds(60.0) == "60 s"


def test_values_show_no_python_syntax() -> None:
    assert value([["robot_at", ["dock"], True]]) == "(robot_at (dock) yes)"
    assert value({"a": None, "b": False}) == "b no"
    assert pairs({"target": "lab", "reached": True, "stamp": 0.0, "empty": []}).startswith(
        "target lab, reached yes, stamp "
    )
