"""Hypothesis checks, at and around their bounds."""

from __future__ import annotations

import pytest

from knowledge.finding import Report
from knowledge.typed_reader import Source, read
from monitoring.check import Check, CheckSpec
from monitoring.filter import FilterState
from monitoring.t_distribution import critical_value


def check(**config: object) -> Check:
    report = Report("test")
    found = read(CheckSpec, config, Source(report), "the check")
    assert found is not None, [str(f) for f in report.findings]
    return found


def value(x: float, n: int = 10, std: float | None = None) -> FilterState:
    return FilterState(x, n, std)


@pytest.mark.parametrize(
    ("config", "passing", "failing"),
    [
        ({"type": "gauss", "mean": 0.1, "std_deviation": 0.25}, [0.35, -0.15, 0.1], [0.36, -0.16]),
        ({"type": "exact", "exact": 1}, [1.0], [1.5, 0.0]),
        ({"type": "not", "exact_not": 1}, [2.0, 0.0], [1.0]),
        ({"type": "greater_than", "greater_than": 0.1}, [0.11], [0.1, -1.0]),
        ({"type": "greather_than", "greather_than": 0.1}, [0.11], [0.1]),
        ({"type": "less_than", "less_than": 0.1}, [0.09, -5.0], [0.1]),
        (
            {"type": "in_between", "lower_bound": 2.0, "upper_bound": 5.1},
            [2.0, 5.1, 3.0],
            [1.99, 5.2],
        ),
        (
            {"type": "not_in_between", "lower_bound": 2.0, "upper_bound": 5.1},
            [1.99, 5.2],
            [2.0, 5.1],
        ),
    ],
    ids=lambda c: c["type"] if isinstance(c, dict) else "",
)
def test_value_checks(
    config: dict[str, object], passing: list[float], failing: list[float]
) -> None:
    found = check(**config)
    assert [found.passes(value(x)) for x in passing] == [True] * len(passing)
    assert [found.passes(value(x)) for x in failing] == [False] * len(failing)


T = {"type": "student_t", "true_mean": 10.0, "std_deviation": 2.0, "significance_level": 0.05}


def test_student_t_accepts_a_mean_inside_the_two_sided_critical_value() -> None:
    # n = 9, s = 2: t = (x - 10) / (2 / 3); t(0.975, 8) = 2.306
    limit = critical_value(0.05, 8) * 2 / 3
    assert critical_value(0.05, 8) == pytest.approx(2.306, abs=5e-4)
    found = check(**T)
    assert found.passes(value(10 + limit - 1e-6, 9))
    assert found.passes(value(10 - limit + 1e-6, 9))
    assert not found.passes(value(10 + limit + 1e-6, 9))
    assert not found.passes(value(10 - limit - 1e-6, 9))


def test_student_t_prefers_the_measured_standard_deviation() -> None:
    found = check(**T)
    assert found.passes(value(11.0, 9))  # t = 1.5 with the configured 2
    assert not found.passes(value(11.0, 9, std=1.0))  # t = 3 with the measured 1


def test_student_t_needs_two_samples() -> None:
    assert not check(**T).passes(value(10.0, 1))


def test_checks_read_as_requirements() -> None:
    assert str(check(type="in_between", lower_bound=8, upper_bound=12)) == "in [8, 12]"
    assert str(check(type="gauss", mean=0, std_deviation=0.1)) == "0 ± 0.1"
    assert str(check(**T)) == "mean 10 at 0.05"


@pytest.mark.parametrize(
    ("config", "message"),
    [
        ({"type": "gauss", "mean": 0}, "the check has no 'std_deviation'"),
        ({"type": "gauss", "mean": 0, "std_deviation": -1}, "must be at least 0, not -1"),
        ({"type": "exact", "exact": "one"}, "'exact' of the check must be a number, not 'one'"),
        ({"type": "exact", "exact": True}, "'exact' of the check must be a number, not true"),
        ({**T, "significance_level": 0}, "must be between 0 and 1 (exclusive), not 0"),
        ({"type": "greater_than", "greater_than": 1, "greather_than": 2}, "has both"),
        ({"type": "less_than", "less_than": 1, "bound": 2}, "unknown key 'bound' in the check"),
        ({"type": "within"}, "unknown check type 'within'"),
    ],
)
def test_a_bad_check_is_reported(config: dict[str, object], message: str) -> None:
    report = Report("test")
    assert read(CheckSpec, config, Source(report), "the check") is None
    assert any(message in f.message for f in report.findings), [f.message for f in report.findings]
