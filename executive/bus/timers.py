"""The timers of a process, on one thread: :func:`later` calls a function after some
seconds of wall time, and the :class:`Timer` it returns takes the call back.

A plan step's timeout, a goal's deadline, the task executor's next wake-up and the
retries of a request were each a ``threading.Timer``: a thread started for every one,
even for one cancelled a moment later. A robot that runs a step every few seconds
started and ended thousands of them an hour, and each thread leaves its stack and a
malloc cache behind for the next (:mod:`tests.benchmarks.soak` measures what a long run
keeps). Here every timer of the process waits on one thread, started with the first
timer. Its calls run one after the other on that thread, so they must be short: dura's
post a job to a worker and return.
"""

from __future__ import annotations

import functools
import heapq
import itertools
import os
import threading
import time
from collections.abc import Callable

Call = Callable[[], object]
COMPACT = 64  # cancelled timers kept in the queue at most, unless half of it is live


class Timer:
    """A call due at a moment (monotonic seconds); :meth:`cancel` takes it back."""

    __slots__ = ("_call", "_timers", "due")

    def __init__(self, due: float, call: Call, timers: Timers) -> None:
        self.due = due
        self._call: Call | None = call
        self._timers = timers

    @property
    def pending(self) -> bool:
        """Tell whether the call is still to come (neither run nor cancelled)."""
        return self._call is not None

    def cancel(self) -> None:
        """Take the call back, unless it runs already (idempotent)."""
        self._timers.cancel(self)


class Timers:
    """Calls functions when they are due, on one daemon thread named ``name``; a call
    that raises is logged, and the calls after it run."""

    def __init__(self, name: str = "timers") -> None:
        self.name = name
        self.threads = 0  # threads started so far (one, once a timer was set)
        self._wake = threading.Condition(threading.Lock())
        self._queue: list[tuple[float, int, Timer]] = []  # a heap, soonest first
        self._order = itertools.count()  # calls due at the same moment run in turn
        self._cancelled = 0  # of the queue's timers
        self._generation = 0  # of the thread that runs the calls; a closed one ends
        self._running = False

    def later(self, seconds: float, call: Call) -> Timer:
        """Call ``call`` after ``seconds`` of wall time (at once if not positive)."""
        timer = Timer(time.monotonic() + max(0.0, seconds), call, self)
        with self._wake:
            heapq.heappush(self._queue, (timer.due, next(self._order), timer))
            if not self._running:
                self._running = True
                self.threads += 1
                threading.Thread(target=self._run, args=(self._generation,), name=self.name,
                                 daemon=True).start()  # fmt: skip
            if self._queue[0][2] is timer:  # sooner than the thread waits for
                self._wake.notify()
        return timer

    def cancel(self, timer: Timer) -> None:
        with self._wake:
            if timer._call is None:
                return
            timer._call = None
            self._cancelled += 1
            if self._cancelled > COMPACT and 2 * self._cancelled > len(self._queue):
                self._queue = [entry for entry in self._queue if entry[2].pending]
                heapq.heapify(self._queue)
                self._cancelled = 0

    def close(self) -> None:
        """Take back every call still to come and end the thread; a timer set after it
        starts a thread again."""
        with self._wake:
            for _, _, timer in self._queue:
                timer._call = None
            self._queue, self._cancelled, self._running = [], 0, False
            self._generation += 1
            self._wake.notify_all()

    def __len__(self) -> int:
        """How many calls are still to come."""
        with self._wake:
            return len(self._queue) - self._cancelled

    def _run(self, generation: int) -> None:
        while (call := self._next(generation)) is not None:
            try:
                call()
            except Exception:
                import logging  # only when a call fails: this module is imported early

                logging.getLogger(__name__).exception("a timer's call %r failed", call)

    def _next(self, generation: int) -> Call | None:
        """Wait for the next call that is due, and take it; None: closed."""
        with self._wake:
            while True:
                if generation != self._generation:
                    return None
                if not self._queue:
                    self._wake.wait()
                    continue
                due, _, timer = self._queue[0]
                if timer._call is None:  # cancelled
                    heapq.heappop(self._queue)
                    self._cancelled -= 1
                    continue
                wait = due - time.monotonic()
                if wait > 0:
                    self._wake.wait(wait)
                    continue
                heapq.heappop(self._queue)
                call, timer._call = timer._call, None
                return call


@functools.cache
def timers() -> Timers:
    """This process's timers (a child process forked from it gets its own)."""
    return Timers()


os.register_at_fork(after_in_child=timers.cache_clear)


def later(seconds: float, call: Call) -> Timer:
    """Call ``call`` after ``seconds`` of wall time, on this process's timer thread."""
    return timers().later(seconds, call)
