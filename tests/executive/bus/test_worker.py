"""The worker thread the task executor and the plan executor run on."""

from __future__ import annotations

import threading

import pytest

from executive.bus.worker import Worker
from knowledge.errors import DuraError


def test_jobs_run_in_order_on_the_worker_thread_and_calls_return_their_result() -> None:
    seen: list[tuple[int, str]] = []
    idle: list[int] = []
    worker = Worker("test worker", after_each=lambda: idle.append(len(seen)))
    worker.start()
    try:
        for i in range(3):
            worker.post(lambda i=i: seen.append((i, threading.current_thread().name)))
        assert worker.call(lambda: len(seen)) == 3
        assert seen == [(0, "test worker"), (1, "test worker"), (2, "test worker")]
        assert idle[:3] == [1, 2, 3]
        assert worker.call(lambda: worker.call(lambda: 42)) == 42  # a call from the thread
    finally:
        worker.stop()
    assert not worker.running


def test_a_failing_job_is_logged_and_a_failing_call_raises_in_the_caller() -> None:
    worker = Worker("test worker")
    worker.start()
    try:
        worker.post(lambda: print(1 / 0))
        with pytest.raises(KeyError):
            worker.call(lambda: {}["missing"])
        assert worker.call(lambda: "alive") == "alive"
        gate = threading.Event()
        worker.post(lambda: gate.wait(5) and None)
        with pytest.raises(DuraError, match=r"^the test worker did not answer in time$"):
            worker.call(lambda: None, timeout=0.05)
        gate.set()
    finally:
        worker.stop()
