"""Helper threads: a job never waits behind another, idle helpers are reused and end
after their linger; and the bus answers a threaded handler's requests on them."""

from __future__ import annotations

import threading

import pytest

from executive.bus.helpers import Helpers
from executive.bus.session import Bus
from tests.conftest import wait_for


def named(prefix: str) -> list[threading.Thread]:
    return [t for t in threading.enumerate() if t.name.startswith(prefix + "-")]


def test_a_job_that_waits_holds_up_no_other() -> None:
    helpers = Helpers("wait")
    release, done = threading.Event(), threading.Event()
    helpers.run(lambda: release.wait(30))
    helpers.run(done.set)
    try:
        assert done.wait(10) and not release.is_set()
        assert helpers.started == 2
    finally:
        release.set()
        helpers.close()


def test_idle_helpers_are_reused_as_many_as_the_most_jobs_at_once() -> None:
    helpers = Helpers("reuse")
    try:
        for _ in range(50):  # one after another: one helper
            done = threading.Event()
            helpers.run(done.set)
            assert done.wait(10)
            assert wait_for(lambda: helpers.idle == 1)
        assert helpers.started == 1
        release = threading.Event()
        running = threading.Semaphore(0)

        def job() -> None:
            running.release()
            release.wait(30)

        for _ in range(4):  # four at once: three more
            helpers.run(job)
        for _ in range(4):
            assert running.acquire(timeout=10)
        release.set()
        assert wait_for(lambda: helpers.idle == 4)
        done = threading.Event()
        helpers.run(done.set)  # on one of the four
        assert done.wait(10)
        assert wait_for(lambda: helpers.idle == 4) and helpers.started == 4
    finally:
        helpers.close()


def test_an_idle_helper_ends_after_its_linger_and_a_later_job_gets_a_new_one() -> None:
    helpers = Helpers("linger", linger=0.05)
    done = threading.Event()
    helpers.run(done.set)
    assert done.wait(10)
    assert wait_for(lambda: helpers.idle == 0 and not named("linger"))
    again = threading.Event()
    helpers.run(again.set)
    assert again.wait(10) and helpers.started == 2
    helpers.close()


def test_closing_ends_the_idle_helpers_and_later_jobs_still_run() -> None:
    helpers = Helpers("close")
    for _ in range(3):
        helpers.run(lambda: None)
    assert wait_for(lambda: helpers.idle >= 1)
    helpers.close()
    assert wait_for(lambda: not named("close")) and helpers.idle == 0
    done = threading.Event()
    helpers.run(done.set)
    assert done.wait(10)
    assert wait_for(lambda: not named("close"))  # it ended after its job


def test_a_job_that_raises_ends_its_helper_and_the_next_job_runs(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    reported: list[BaseException | None] = []
    monkeypatch.setattr(threading, "excepthook", lambda args: reported.append(args.exc_value))
    helpers = Helpers("raise")

    def fail() -> None:
        raise ValueError("broken")

    helpers.run(fail)
    assert wait_for(lambda: len(reported) == 1) and isinstance(reported[0], ValueError)
    done = threading.Event()
    helpers.run(done.set)
    assert done.wait(10) and helpers.started == 2
    helpers.close()


def test_map_gives_the_results_in_order_and_the_first_error_after_all_ended() -> None:
    helpers = Helpers("map")
    try:
        together = threading.Barrier(5, timeout=10)  # all five run at once

        def square(n: int) -> int:
            together.wait()
            return n * n

        assert helpers.map(square, [1, 2, 3, 4, 5]) == [1, 4, 9, 16, 25]
        assert helpers.map(square, []) == []
        ended: list[int] = []

        def check(n: int) -> int:
            if n % 2:
                raise ValueError(f"odd {n}")
            ended.append(n)
            return n

        with pytest.raises(ValueError, match=r"^odd 1$"):
            helpers.map(check, [1, 2, 3, 4])
        assert sorted(ended) == [2, 4]
    finally:
        helpers.close()


def test_the_bus_answers_a_threaded_handlers_requests_on_reused_helpers(endpoint: str) -> None:
    release = threading.Event()
    served_on: set[str] = set()

    def handler(request: dict[str, object]) -> dict[str, object]:
        served_on.add(threading.current_thread().name)
        if request.get("wait"):  # a handler that waits holds up no other request
            release.wait(30)
        return {"n": request.get("n")}

    with (
        Bus("robot", name="server", endpoint=endpoint, listen=True) as server,
        Bus("robot", name="client", endpoint=endpoint) as client,
    ):
        server.serve("echo", handler, threaded=True)
        assert wait_for(lambda: _answers(client), 10)
        waiting = threading.Thread(target=client.request, args=("echo", {"wait": True}))
        waiting.start()
        try:
            for n in range(100):
                assert client.request("echo", {"n": n}) == {"n": n}
            # a thread each would be 101; a reply can reach the client a moment before its
            # helper is idle again, so the next request may start another: a few
            assert all(name.startswith("bus-request-") for name in served_on)
            assert len(served_on) <= 10, sorted(served_on)
        finally:
            release.set()
            waiting.join()
    assert wait_for(lambda: not named("bus-request"))  # the bus closed: its helpers end


def _answers(bus: Bus) -> bool:
    try:
        bus.request("echo", {}, timeout=0.5)
    except Exception:
        return False
    return True
