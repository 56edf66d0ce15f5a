"""Helper threads for work that may wait: each job starts at once, on an idle helper or
on a new one, and a helper idle for ``linger`` seconds ends.

A job that waits (for other messages, for a process) must not hold up the jobs after
it, so a queue in front of a fixed number of threads will not do; a thread of its own
for every job is what the bus did, and at a request every few milliseconds (a client
polling a goal, the dashboard) that is hundreds of threads started and ended a minute.
Every one of them takes a stack and a malloc cache, which glibc keeps for the next one,
and the churn fragments the long-running executive's heap (:mod:`tests.benchmarks.soak`
measures it). Helpers are reused instead: as many as the most jobs at once, and they
go when no longer needed.
"""

from __future__ import annotations

import functools
import threading
from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING, Any, TypeVar

if TYPE_CHECKING:
    import queue  # imported where a helper waits: a client's Bus never does

LINGER = 30.0  # seconds an idle helper waits for a job before it ends

Job = Callable[[], None]
T = TypeVar("T")
R = TypeVar("R")


class Helpers:
    """Runs jobs on reused threads (daemons, named ``<name>-<n>``), never behind another
    job; a job's exception is the job's to catch (it ends its helper, and Python's
    ``threading.excepthook`` reports it)."""

    def __init__(self, name: str, *, linger: float = LINGER) -> None:
        self.name = name
        self.linger = linger
        self.started = 0  # helpers started so far
        self._lock = threading.Lock()
        self._idle: list[queue.SimpleQueue[Job | None]] = []  # the newest idle last
        self._closed = False

    def run(self, job: Job) -> None:
        """Start ``job`` now, on an idle helper or a new one."""
        with self._lock:
            if self._idle:
                self._idle.pop().put(job)  # the helper idle for the shortest time
                return
            self.started += 1
            number = self.started
        threading.Thread(
            target=self._serve, args=(job,), name=f"{self.name}-{number}", daemon=True
        ).start()

    def map(self, fn: Callable[[T], R], items: Sequence[T]) -> list[R]:
        """``fn`` of every item, all at once on helpers; the results in order. Should any
        call raise, the first such exception is raised once all of them ended."""
        import queue

        ended: queue.SimpleQueue[tuple[int, bool, Any]] = queue.SimpleQueue()

        def call(index: int, item: T) -> None:
            try:
                ended.put((index, True, fn(item)))
            except BaseException as e:  # handed to the caller
                ended.put((index, False, e))

        for index, item in enumerate(items):
            self.run(functools.partial(call, index, item))
        outcomes = sorted(ended.get() for _ in items)
        for _, ok, value in outcomes:
            if not ok:
                raise value
        return [value for _, _, value in outcomes]

    @property
    def idle(self) -> int:
        """How many helpers wait for a job."""
        with self._lock:
            return len(self._idle)

    def close(self) -> None:
        """End the idle helpers, and each busy one after its job (idempotent); later
        jobs still run, each on a helper that ends after it."""
        with self._lock:
            self._closed = True
            idle, self._idle = self._idle, []
        for inbox in idle:
            inbox.put(None)

    def _serve(self, job: Job | None) -> None:
        import queue

        inbox: queue.SimpleQueue[Job | None] = queue.SimpleQueue()
        while job is not None:
            job()
            job = self._next(inbox)

    def _next(self, inbox: queue.SimpleQueue[Job | None]) -> Job | None:
        """Wait for the next job as an idle helper; None: end."""
        with self._lock:
            if self._closed:
                return None
            self._idle.append(inbox)
        import queue

        try:
            return inbox.get(timeout=self.linger)
        except queue.Empty:
            with self._lock:
                if inbox in self._idle:  # nobody chose it meanwhile: it ends
                    self._idle.remove(inbox)
                    return None
            return inbox.get()  # it was chosen just as its time was up
