"""The schedule of a rate loop (:meth:`Component.at_rate`): absolute deadlines, and no
burst after a stall."""

from __future__ import annotations

import itertools

import pytest

from executive.sdk.component import next_due

PERIOD = 0.1


def starts(steps: int, *, stalled_at: int = -1, stall: float = 0.0) -> list[float]:
    """When each step of a loop starts, its steps taking a tenth of a period, and the
    process stopped for ``stall`` seconds while it waits after step ``stalled_at``."""
    due, now, started = 0.0, 0.0, []
    for step in range(steps):
        started.append(now)
        now += PERIOD / 10  # the step
        due = next_due(due, PERIOD, started[-1], now)
        now = max(now, due)  # the wait
        if step == stalled_at:
            now += stall  # stopped (SIGSTOP), continued
    return started


def test_a_loop_that_keeps_up_steps_on_its_absolute_schedule() -> None:
    assert starts(50) == pytest.approx([i * PERIOD for i in range(50)])


@pytest.mark.parametrize("stall", [1.01 * PERIOD, 1.5 * PERIOD, 5 * PERIOD, 100 * PERIOD])
def test_after_a_stall_the_next_step_comes_a_period_after_the_late_one(stall: float) -> None:
    started = starts(30, stalled_at=9, stall=stall)
    late = started[10]
    assert late == pytest.approx(10 * PERIOD + stall)  # at once when continued
    gaps = [b - a for a, b in itertools.pairwise(started[10:])]
    assert min(gaps) == pytest.approx(PERIOD)  # no burst: no shorter period after it


def test_a_long_step_is_followed_at_once_and_the_loop_keeps_its_rate_after_it() -> None:
    due = next_due(0.0, PERIOD, 0.0, 0.25)  # a step of two and a half periods
    assert due == 0.25
    due = next_due(due, PERIOD, 0.25, 0.26)  # the next, on time
    assert due == pytest.approx(0.35)


def test_a_loop_less_than_a_period_behind_catches_up_without_drifting() -> None:
    started = starts(20, stalled_at=4, stall=0.5 * PERIOD)
    assert started[5] == pytest.approx(5.5 * PERIOD)  # late by half a period
    assert started[6] == pytest.approx(6 * PERIOD)  # back on the schedule
    assert started[19] == pytest.approx(19 * PERIOD)
