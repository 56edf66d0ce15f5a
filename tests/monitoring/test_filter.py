"""Filters, with values worked out by hand."""

from __future__ import annotations

import math

import pytest

from monitoring.filter import FilterConfig, FilterState


def filtered(values: list[float], **config: object) -> FilterState:
    f = FilterConfig(**config).make()  # type: ignore[arg-type]
    f.extend(values)
    state = f.state()
    assert state is not None
    return state


def test_nofilter_gives_the_last_value() -> None:
    state = filtered([3, 1, 2], type="nofilter")
    assert (state.value, state.sample_size) == (2, 3)


def test_a_windowed_mean_averages_the_last_values() -> None:
    state = filtered([1, 2, 3, 4], type="mean", window_size=3)
    assert (state.value, state.sample_size) == (3.0, 3)


def test_a_mean_without_a_window_averages_everything_since_the_reset() -> None:
    state = filtered([1, 2, 3, 4], type="mean")
    assert (state.value, state.sample_size) == (2.5, 4)


@pytest.mark.parametrize(
    ("values", "window", "median"),
    [([5, 1, 4, 2, 8], 4, 3.0), ([9, 1, 7, 3], 3, 3.0)],
    ids=["even window", "odd window"],
)
def test_the_median_of_the_window(values: list[float], window: int, median: float) -> None:
    assert filtered(values, type="median", window_size=window).value == median


@pytest.mark.parametrize(("k", "mean"), [(2, 4.5), (3, 4.0), (6, 32 / 6)])
def test_kmeans_averages_the_k_central_values_of_the_sorted_window(k: int, mean: float) -> None:
    # sorted window: 1 3 4 5 9 10
    state = filtered([10, 1, 5, 3, 9, 4], type="kmeans", window_size=6, k_size=k)
    assert state.value == pytest.approx(mean, rel=1e-15)


def test_ewma_blends_each_value_in_by_the_decay_rate() -> None:
    # 4, then 4 * 0.5 + 8 * 0.5 = 6, then 6 * 0.5 + 0 * 0.5 = 3
    assert filtered([4, 8, 0], type="ewma", decay_rate=0.5).value == 3.0


def test_ewma_over_a_window_starts_again_from_the_windows_first_value() -> None:
    # window [8, 0]: 8, then 8 * 0.75 + 0 * 0.25 = 6
    assert filtered([4, 8, 0], type="ewma", decay_rate=0.25, window_size=2).value == 6.0


SAMPLE = [2, 4, 4, 4, 5, 5, 7, 9]  # mean 5, squared deviations 32


@pytest.mark.parametrize("window", [None, 8], ids=["cumulative", "window"])
def test_std_is_the_sample_standard_deviation(window: int | None) -> None:
    state = filtered(SAMPLE, type="mean", window_size=window, deviation_type="std")
    assert state.std == pytest.approx(math.sqrt(32 / 7), rel=1e-14)
    assert state.value == 5.0


def test_std_needs_two_values() -> None:
    assert filtered([3], type="mean", deviation_type="std").std is None
    assert filtered([3], type="mean", window_size=4, deviation_type="std").std is None


@pytest.mark.parametrize("window", [None, 3], ids=["cumulative", "window"])
def test_min_max_holds_for_negative_values(window: int | None) -> None:
    state = filtered([5, -3, -7, -1], type="median", window_size=3, deviation_type="min_max")
    assert (state.minimum, state.maximum) == (-7, -1)
    state = filtered([-3, -7, -1], type="mean", window_size=window, deviation_type="min_max")
    assert (state.minimum, state.maximum) == (-7, -1)


def test_a_reset_filter_has_no_state() -> None:
    f = FilterConfig("mean", deviation_type="std").make()
    assert f.state() is None
    f.extend([1, 2])
    f.reset()
    assert f.state() is None
    f.update(7)
    assert f.state() == FilterState(7.0, 1, None)
