"""The timers of a process: calls run when due, in order, on one thread; a cancelled
call never runs and is not kept; a failing call stops no other; a forked child has
timers of its own; and the clock's robot-time timers are these."""

from __future__ import annotations

import logging
import multiprocessing
import random
import threading
import time
import tracemalloc
from collections.abc import Iterator

import pytest

from executive.bus.clock import Clock
from executive.bus.timers import Timers, later, timers
from tests.conftest import wait_for


@pytest.fixture
def box() -> Iterator[Timers]:
    """Timers of the test's own, closed after it."""
    own = Timers("test-timers")
    yield own
    own.close()


def test_calls_run_in_the_order_they_are_due_on_one_thread(box: Timers) -> None:
    ran: list[tuple[int, int]] = []
    dues: list[float] = []
    for n in range(40):
        timer = box.later(random.uniform(0.0, 0.3),
                          lambda n=n: ran.append((n, threading.get_ident())))  # fmt: skip
        dues.append(timer.due)
    assert wait_for(lambda: len(ran) == len(dues), 10)
    assert [dues[n] for n, _ in ran] == sorted(dues)
    assert len({ident for _, ident in ran}) == 1 and box.threads == 1


def test_a_sooner_call_set_while_the_thread_waits_for_a_later_one_runs_first(box: Timers) -> None:
    late, soon = threading.Event(), threading.Event()
    box.later(3600.0, late.set)
    time.sleep(0.05)  # the thread waits for the hour
    box.later(0.0, soon.set)
    assert soon.wait(5) and not late.is_set()
    assert len(box) == 1


def test_a_cancelled_call_never_runs_and_cancelling_is_idempotent(box: Timers) -> None:
    kept, taken = threading.Event(), threading.Event()
    timer = box.later(0.2, taken.set)
    box.later(0.4, kept.set)
    timer.cancel()
    timer.cancel()
    assert not timer.pending
    assert kept.wait(5) and not taken.is_set()
    ran = box.later(0.0, lambda: None)
    assert wait_for(lambda: not ran.pending)
    ran.cancel()  # after it ran: nothing happens
    assert len(box) == 0


def test_cancelled_timers_are_not_kept_until_they_would_have_been_due(box: Timers) -> None:
    """A step's timeout is set and cancelled at every step: an hour's worth of them is
    not kept for the hour."""
    box.later(3600.0, lambda: None).cancel()  # the thread exists before measuring
    tracemalloc.start()
    before, _ = tracemalloc.get_traced_memory()
    for _ in range(20_000):
        box.later(3600.0, lambda: None).cancel()
    after, _ = tracemalloc.get_traced_memory()
    tracemalloc.stop()
    assert len(box) == 0
    assert after - before < 64 * 1024, after - before  # 20,000 kept would be > 2 MB


def test_a_call_that_raises_is_logged_and_the_next_one_runs(
    box: Timers, caplog: pytest.LogCaptureFixture
) -> None:
    after = threading.Event()

    def broken() -> None:
        raise RuntimeError("boom")

    with caplog.at_level(logging.ERROR, logger="executive.bus.timers"):
        box.later(0.0, broken)
        box.later(0.05, after.set)
        assert after.wait(5)
    assert any("boom" in (r.exc_text or "") for r in caplog.records), caplog.records
    assert box.threads == 1


def test_closing_ends_the_thread_and_drops_what_was_to_come() -> None:
    box = Timers("closing")
    never = threading.Event()
    box.later(0.3, never.set)
    assert wait_for(lambda: any(t.name == "closing" for t in threading.enumerate()))
    box.close()
    assert wait_for(lambda: not any(t.name == "closing" for t in threading.enumerate()))
    assert not never.wait(0.5) and len(box) == 0
    again = threading.Event()
    box.later(0.0, again.set)  # a thread again
    assert again.wait(5) and box.threads == 2
    box.close()


def _fires_in_child(ok: multiprocessing.SimpleQueue[bool]) -> None:
    fired = threading.Event()
    later(0.0, fired.set)
    ok.put(fired.wait(5))


def test_a_forked_child_has_timers_of_its_own() -> None:
    later(0.0, lambda: None)  # the parent's thread runs
    context = multiprocessing.get_context("fork")
    ok: multiprocessing.SimpleQueue[bool] = context.SimpleQueue()
    child = context.Process(target=_fires_in_child, args=(ok,))
    child.start()
    child.join(20)
    assert child.exitcode == 0 and ok.get() is True


def test_the_clocks_timers_run_on_the_process_timer_thread() -> None:
    fired: list[int] = []
    started = timers().threads
    for n in range(100):
        Clock(1000.0).timer(n, lambda n=n: fired.append(threading.get_ident()))  # n ms
    assert wait_for(lambda: len(fired) == 100, 10)
    assert len(set(fired)) == 1 and timers().threads == max(1, started)
