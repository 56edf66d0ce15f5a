"""A worker thread: the one thread that touches an object's state, running jobs in the
order they were posted. Other threads post jobs, or call a function there and wait for
its result (the task executor and the plan executor are built on it)."""

from __future__ import annotations

import logging
import queue
import threading
from collections.abc import Callable
from typing import Any, TypeVar

from knowledge.errors import DuraError

T = TypeVar("T")
log = logging.getLogger(__name__)


class Worker:
    """Runs posted jobs one after the other on its own thread.

    Args:
        name: the thread's name, and who "did not answer" when a call times out.
        after_each: run on the thread after every job (e.g. to tell that it is idle).
    """

    def __init__(self, name: str, after_each: Callable[[], None] | None = None) -> None:
        self.name = name
        self._after_each = after_each
        self._queue: queue.Queue[Callable[[], None] | None] = queue.Queue()
        self._thread: threading.Thread | None = None

    @property
    def running(self) -> bool:
        return self._thread is not None

    def start(self) -> None:
        if self._thread is None:
            self._thread = threading.Thread(target=self._loop, name=self.name, daemon=True)
            self._thread.start()

    def stop(self) -> None:
        """Run what was posted so far, then end the thread; idempotent."""
        if self._thread is None:
            return
        self._queue.put(None)
        if threading.current_thread() is not self._thread:
            self._thread.join()
        self._thread = None

    def post(self, job: Callable[[], None]) -> None:
        """Run ``job`` on the thread, later."""
        self._queue.put(job)

    def call(self, fn: Callable[[], T], timeout: float | None = None) -> T:
        """Run ``fn`` on the thread and return its result (or raise its exception).

        Raises:
            DuraError: no answer within ``timeout`` seconds.
        """
        if threading.current_thread() is self._thread:
            return fn()
        done = threading.Event()
        box: list[tuple[bool, Any]] = []

        def job() -> None:
            try:
                box.append((True, fn()))
            except BaseException as e:  # handed to the caller
                box.append((False, e))
            finally:
                done.set()

        self._queue.put(job)
        if not done.wait(timeout):
            raise DuraError(f"the {self.name} did not answer in time")
        ok, value = box[0]
        if not ok:
            raise value
        return value  # type: ignore[no-any-return]

    def _loop(self) -> None:
        while True:
            job = self._queue.get()
            if job is None:
                return
            try:
                job()
            except Exception:  # one failed job must not end the worker
                log.exception("%s: a step failed", self.name)
            if self._after_each is not None:
                self._after_each()
