"""Hypothesis checks: does a filtered measurement meet a requirement (thesis 6.2.3)?

A check configuration is the thesis/tug mapping, e.g.
``{type: in_between, lower_bound: 2.0, upper_bound: 5.1}``: :data:`CheckSpec` reads it (its
``type`` names the class). Checks are frozen values; :meth:`Check.passes` looks at a
:class:`~monitoring.filter.FilterState`.

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
from typing import Annotated

from knowledge.conventions import AtLeast, Inside, Key, Tagged
from knowledge.typed_reader import Entry
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


Deviation = Annotated[float, AtLeast(0.0)]


@dataclass(frozen=True)
class StudentT(Check):
    true_mean: float
    std_deviation: Deviation
    significance_level: Annotated[float, Inside(0.0, 1.0)]

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
    std_deviation: Deviation

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
    bound: Annotated[float, Key("greater_than", "greather_than")]  # tug's spelling too

    def passes(self, state: FilterState) -> bool:
        return state.value > self.bound

    def __str__(self) -> str:
        return f"> {self.bound:g}"


@dataclass(frozen=True)
class LessThan(Check):
    bound: Annotated[float, Key("less_than")]

    def passes(self, state: FilterState) -> bool:
        return state.value < self.bound

    def __str__(self) -> str:
        return f"< {self.bound:g}"


@dataclass(frozen=True)
class Interval(Check):
    """A check of a closed interval."""

    lower_bound: float
    upper_bound: float

    def after_read(self, entry: Entry) -> Interval | None:
        if self.lower_bound > self.upper_bound:
            entry.error(
                "lower_bound",
                f"{entry.what}: 'lower_bound' {self.lower_bound:g} exceeds 'upper_bound' "
                f"{self.upper_bound:g}",
            )
            return None
        return self


@dataclass(frozen=True)
class InBetween(Interval):
    def passes(self, state: FilterState) -> bool:
        return self.lower_bound <= state.value <= self.upper_bound

    def __str__(self) -> str:
        return f"in [{self.lower_bound:g}, {self.upper_bound:g}]"


@dataclass(frozen=True)
class NotInBetween(Interval):
    def passes(self, state: FilterState) -> bool:
        return not self.lower_bound <= state.value <= self.upper_bound

    def __str__(self) -> str:
        return f"outside [{self.lower_bound:g}, {self.upper_bound:g}]"


CHECKS: dict[str, type[Check]] = {
    "student_t": StudentT,
    "gauss": Gauss,
    "exact": Exact,
    "not": Not,
    "greater_than": GreaterThan,
    "less_than": LessThan,
    "in_between": InBetween,
    "not_in_between": NotInBetween,
}
LEGACY = {"greather_than": "greater_than"}

CheckSpec = Annotated[Check, Tagged("type", "check type", CHECKS, legacy=LEGACY)]
"""A check as configured: its ``type`` names the class, the other keys its fields."""
