"""Filters: smooth an observer's measurements before its hypothesis checks (thesis 6.2.3).

A filter configuration is the thesis/tug mapping::

    {type: mean, window_size: 200, deviation_type: std}

Value filters: ``nofilter`` (the last value), ``mean`` (over the window, or over every
value since the last reset without one), ``median`` (window), ``kmeans`` (the mean of
the ``k_size`` central values of the sorted window), ``ewma`` (``x = x (1 - d) + v d``
with ``decay_rate`` d, recomputed from the window's first value when there is one).
Deviation filters, over the same values: ``std`` (sample standard deviation, n - 1)
and ``min_max`` (smallest and largest value).

Values are appended in O(1); the filtered value is computed when it is asked for,
once per observer loop.
"""

from __future__ import annotations

import math
import statistics
from collections import deque
from collections.abc import Iterable
from dataclasses import dataclass
from typing import Annotated

from knowledge.conventions import AtLeast, Inside, NonEmpty, OneOf, Required, When
from knowledge.typed_reader import Entry

Text = Annotated[str, NonEmpty(blank=True)]
"""A text of an observer configuration: not empty (blanks are text, refused later)."""

VALUE_FILTERS = ("nofilter", "mean", "median", "kmeans", "ewma")
DEVIATION_FILTERS = ("std", "min_max")
WINDOWED = ("median", "kmeans")  # these need a window


@dataclass(frozen=True)
class FilterConfig:
    """A filter as configured; :meth:`make` gives a fresh filter."""

    type: Annotated[Text, Required(), OneOf(VALUE_FILTERS, "filter type")] = "nofilter"
    window_size: Annotated[int | None, AtLeast(2)] = None
    k_size: Annotated[int | None, AtLeast(1), Required(), When("type", "kmeans")] = None
    decay_rate: Annotated[float | None, Inside(0.0, 1.0), Required(), When("type", "ewma")] = None
    deviation_type: Annotated[Text | None, OneOf(DEVIATION_FILTERS, "deviation type")] = None

    def make(self) -> Filter:
        return Filter(self)

    def after_read(self, entry: Entry) -> FilterConfig:
        """Report a window a windowed filter lacks, and a k larger than the window."""
        kind, window, k = self.type, self.window_size, self.k_size
        if kind in WINDOWED and window is None and not entry.has("window_size"):
            entry.error(None, f"{entry.what} ({kind}) has no 'window_size'")
        if k is not None and window is not None and k > window:
            entry.error("k_size", f"'k_size' of {entry.what} ({k}) exceeds its window ({window})")
        return self


@dataclass(frozen=True)
class FilterState:
    """What a filter says about its values: the filtered value and the deviation.

    ``std`` is set for ``deviation_type: std`` (with at least two values), ``minimum``
    and ``maximum`` for ``min_max``. ``sample_size`` counts the values the state is
    computed from.
    """

    value: float
    sample_size: int
    std: float | None = None
    minimum: float | None = None
    maximum: float | None = None


class Filter:
    """The values of one measured quantity, filtered as configured."""

    def __init__(self, config: FilterConfig) -> None:
        self.config = config
        self._window: deque[float] | None = (
            deque(maxlen=config.window_size) if config.window_size else None
        )
        self.reset()

    def reset(self) -> None:
        """Forget every value."""
        if self._window is not None:
            self._window.clear()
        self._count = 0
        self._last = 0.0
        self._sum = 0.0  # cumulative mean
        self._ewma = 0.0  # cumulative ewma
        self._mean = 0.0  # Welford, cumulative std
        self._m2 = 0.0
        self._min = math.inf
        self._max = -math.inf

    def update(self, value: float) -> None:
        """Add one value."""
        self._count += 1
        self._last = value
        if self._window is not None:
            self._window.append(value)
            return
        self._sum += value
        decay = self.config.decay_rate
        if decay is not None:
            self._ewma = value if self._count == 1 else self._ewma * (1.0 - decay) + value * decay
        delta = value - self._mean
        self._mean += delta / self._count
        self._m2 += delta * (value - self._mean)
        self._min = min(self._min, value)
        self._max = max(self._max, value)

    def extend(self, values: Iterable[float]) -> None:
        for value in values:
            self.update(value)

    @property
    def sample_size(self) -> int:
        return len(self._window) if self._window is not None else self._count

    def state(self) -> FilterState | None:
        """The filtered value and deviation, or ``None`` before the first value."""
        if self._count == 0:
            return None
        window = list(self._window) if self._window is not None else None
        std = minimum = maximum = None
        if self.config.deviation_type == "std":
            if window is not None:
                std = statistics.stdev(window) if len(window) > 1 else None
            elif self._count > 1:
                std = math.sqrt(self._m2 / (self._count - 1))
        elif self.config.deviation_type == "min_max":
            minimum, maximum = (min(window), max(window)) if window else (self._min, self._max)
        return FilterState(self._value(window), self.sample_size, std, minimum, maximum)

    def _value(self, window: list[float] | None) -> float:
        kind = self.config.type
        if kind == "nofilter":
            return self._last
        if kind == "ewma":
            if window is None:
                return self._ewma
            decay = self.config.decay_rate or 0.0
            value = window[0]
            for v in window[1:]:
                value = value * (1.0 - decay) + v * decay
            return value
        if window is None:  # mean without a window
            return self._sum / self._count
        if kind == "mean":
            return math.fsum(window) / len(window)
        if kind == "median":
            return float(statistics.median(window))
        ordered = sorted(window)  # kmeans
        k = min(self.config.k_size or len(ordered), len(ordered))
        start = (len(ordered) - k) // 2
        return math.fsum(ordered[start : start + k]) / k
