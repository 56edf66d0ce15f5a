"""Hypothesis checks: does a filtered measurement meet a requirement (thesis 6.2.3)?

A check configuration is the thesis/tug mapping, e.g.
``{type: in_between, lower_bound: 2.0, upper_bound: 5.1}``. Checks are frozen values;
:meth:`Check.passes` looks at a :class:`~monitoring.filter.FilterState`.

=================  ===============================================================
``student_t``      two-sided one-sample t-test of the filtered value against
                   ``true_mean`` at ``significance_level``; the deviation is the
                   filter's sample std (``deviation_type: std``), else
                   ``std_deviation``; needs at least two samples
``gauss``          ``|x - mean| <= std_deviation``
``exact``          ``x == exact``
``not``            ``x != exact_not``
``greater_than``   ``x > greater_than`` (the legacy spelling ``greather_than`` too)
``less_than``      ``x < less_than``
``in_between``     ``lower_bound <= x <= upper_bound``
``not_in_between`` ``x < lower_bound or x > upper_bound``
=================  ===============================================================
"""

from __future__ import annotations

import math
from abc import ABC, abstractmethod
from dataclasses import dataclass

from knowledge.yamlsource import did_you_mean
from monitoring.config_entry import Entry
from monitoring.filter import FilterState
from monitoring.t_distribution import two_sided_p


class Check(ABC):
    """One requirement on a filtered measurement."""

    @abstractmethod
    def passes(self, state: FilterState) -> bool:
        """Whether the measurement meets the requirement."""

    @abstractmethod
    def __str__(self) -> str:
        """The requirement as people read it, e.g. ``in [8, 12]``."""


@dataclass(frozen=True)
class StudentT(Check):
    true_mean: float
    std_deviation: float
    significance_level: float

    def passes(self, state: FilterState) -> bool:
        n = state.sample_size
        if n < 2:
            return False
        std = state.std if state.std is not None else self.std_deviation
        difference = state.value - self.true_mean
        if std == 0.0:
            return difference == 0.0
        t = difference / (std / math.sqrt(n))
        return two_sided_p(t, n - 1) >= self.significance_level

    def __str__(self) -> str:
        return f"mean {self.true_mean:g} at {self.significance_level:g}"


@dataclass(frozen=True)
class Gauss(Check):
    mean: float
    std_deviation: float

    def passes(self, state: FilterState) -> bool:
        return abs(state.value - self.mean) <= self.std_deviation

    def __str__(self) -> str:
        return f"{self.mean:g} ± {self.std_deviation:g}"


@dataclass(frozen=True)
class Exact(Check):
    exact: float

    def passes(self, state: FilterState) -> bool:
        return state.value == self.exact

    def __str__(self) -> str:
        return f"= {self.exact:g}"


@dataclass(frozen=True)
class Not(Check):
    exact_not: float

    def passes(self, state: FilterState) -> bool:
        return state.value != self.exact_not

    def __str__(self) -> str:
        return f"≠ {self.exact_not:g}"


@dataclass(frozen=True)
class GreaterThan(Check):
    bound: float

    def passes(self, state: FilterState) -> bool:
        return state.value > self.bound

    def __str__(self) -> str:
        return f"> {self.bound:g}"


@dataclass(frozen=True)
class LessThan(Check):
    bound: float

    def passes(self, state: FilterState) -> bool:
        return state.value < self.bound

    def __str__(self) -> str:
        return f"< {self.bound:g}"


@dataclass(frozen=True)
class InBetween(Check):
    lower_bound: float
    upper_bound: float

    def passes(self, state: FilterState) -> bool:
        return self.lower_bound <= state.value <= self.upper_bound

    def __str__(self) -> str:
        return f"in [{self.lower_bound:g}, {self.upper_bound:g}]"


@dataclass(frozen=True)
class NotInBetween(Check):
    lower_bound: float
    upper_bound: float

    def passes(self, state: FilterState) -> bool:
        return not self.lower_bound <= state.value <= self.upper_bound

    def __str__(self) -> str:
        return f"outside [{self.lower_bound:g}, {self.upper_bound:g}]"


CHECKS = (
    "student_t",
    "gauss",
    "exact",
    "not",
    "greater_than",
    "less_than",
    "in_between",
    "not_in_between",
)
LEGACY = {"greather_than": "greater_than"}


def _bounds(entry: Entry) -> tuple[float, float] | None:
    lower = entry.number("lower_bound", required=True)
    upper = entry.number("upper_bound", required=True)
    if lower is None or upper is None:
        return None
    if lower > upper:
        entry.error(
            "lower_bound", f"{entry.what}: 'lower_bound' {lower:g} exceeds 'upper_bound' {upper:g}"
        )
        return None
    return lower, upper


def _greater_than(entry: Entry) -> GreaterThan | None:
    keys = [k for k in ("greater_than", *LEGACY) if entry.has(k)]
    if len(keys) > 1:
        entry.error(keys[1], f"{entry.what} has both 'greater_than' and 'greather_than'")
        entry.get(keys[1])
    bound = entry.number(keys[0] if keys else "greater_than", required=True)
    return GreaterThan(bound) if bound is not None else None


def _make(kind: str, entry: Entry) -> Check | None:
    if kind == "student_t":
        mean = entry.number("true_mean", required=True)
        std = entry.number("std_deviation", required=True, minimum=0.0)
        level = entry.number("significance_level", required=True, above=0.0, below=1.0)
        if mean is None or std is None or level is None:
            return None
        return StudentT(mean, std, level)
    if kind == "gauss":
        mean = entry.number("mean", required=True)
        std = entry.number("std_deviation", required=True, minimum=0.0)
        return Gauss(mean, std) if mean is not None and std is not None else None
    if kind == "exact":
        exact = entry.number("exact", required=True)
        return Exact(exact) if exact is not None else None
    if kind == "not":
        exact_not = entry.number("exact_not", required=True)
        return Not(exact_not) if exact_not is not None else None
    if kind == "greater_than":
        return _greater_than(entry)
    if kind == "less_than":
        bound = entry.number("less_than", required=True)
        return LessThan(bound) if bound is not None else None
    bounds = _bounds(entry)  # in_between, not_in_between
    if bounds is None:
        return None
    return InBetween(*bounds) if kind == "in_between" else NotInBetween(*bounds)


def read_check(entry: Entry | None) -> Check | None:
    """A check from its configuration; ``None`` if invalid (the problems are reported)."""
    if entry is None or not entry.valid:
        return None
    errors = len(entry.source.report.errors)
    kind = entry.text("type", required=True)
    if kind is None:
        return None
    kind = LEGACY.get(kind, kind)
    if kind not in CHECKS:
        entry.error(
            "type",
            f"unknown check type '{kind}' in {entry.what} "
            f"(choose from {', '.join(CHECKS)}){did_you_mean(kind, CHECKS)}",
        )
        return None
    check = _make(kind, entry)
    entry.close()
    return check if len(entry.source.report.errors) == errors else None
