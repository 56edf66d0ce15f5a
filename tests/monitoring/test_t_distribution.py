"""Student's t distribution against printed tables and closed forms."""

from __future__ import annotations

import math

import pytest

from monitoring.t_distribution import critical_value, incomplete_beta, two_sided_p


@pytest.mark.parametrize(
    ("level", "df", "table"),
    [
        (0.05, 1, 12.706),
        (0.05, 2, 4.303),
        (0.05, 5, 2.571),
        (0.05, 10, 2.228),
        (0.05, 30, 2.042),
        (0.01, 5, 4.032),
        (0.01, 20, 2.845),
        (0.10, 20, 1.725),
        (0.10, 120, 1.658),
    ],
)
def test_two_sided_critical_values_match_the_table(level: float, df: int, table: float) -> None:
    assert critical_value(level, df) == pytest.approx(table, abs=5e-4)


@pytest.mark.parametrize("t", [0.0, 0.3, 1.0, 2.5, 12.706, 100.0])
def test_one_and_two_degrees_of_freedom_match_their_closed_forms(t: float) -> None:
    assert two_sided_p(t, 1) == pytest.approx(1 - 2 / math.pi * math.atan(t), abs=1e-13)
    assert two_sided_p(t, 2) == pytest.approx(1 - t / math.sqrt(2 + t * t), abs=1e-13)


def test_the_incomplete_beta_function_matches_exact_values() -> None:
    # I_0.4(2, 3) = sum over j = 2..4 of C(4, j) 0.4^j 0.6^(4 - j)
    assert incomplete_beta(2, 3, 0.4) == pytest.approx(0.5248, abs=1e-14)
    assert incomplete_beta(1, 1, 0.37) == pytest.approx(0.37, abs=1e-14)
    assert incomplete_beta(3, 1, 0.9) == pytest.approx(0.729, abs=1e-14)
    assert incomplete_beta(2, 3, 0.0) == 0.0 and incomplete_beta(2, 3, 1.0) == 1.0


def test_the_tail_is_symmetric_and_falls_with_t() -> None:
    assert two_sided_p(-2.0, 7) == two_sided_p(2.0, 7)
    assert two_sided_p(1.0, 7) > two_sided_p(2.0, 7) > two_sided_p(3.0, 7)


def test_nonsense_arguments_are_refused() -> None:
    with pytest.raises(ValueError, match="significance level"):
        critical_value(1.5, 3)
    with pytest.raises(ValueError, match="degrees of freedom"):
        two_sided_p(1.0, 0)
