"""A polled subscription (executive.bus.polled): messages wait for their taker, each with
the time it arrived, stamped when Python saw it or else estimated from its sender's
clock (SenderClocks)."""

from __future__ import annotations

import threading
import time
from collections.abc import Iterator
from typing import Any

import pytest

from executive.bus.message import Message
from executive.bus.polled import SENDERS, SPAN, SenderClocks
from executive.bus.session import Bus, Handler
from tests.conftest import wait_for

S = 1_000_000_000  # a second in ns


def test_a_late_take_does_not_make_a_message_late() -> None:
    clocks = SenderClocks()
    offset = -2 * S  # the sender's clock is 2 s behind; the transport takes 1 ms
    clocks.learn("lidar", 10 * S + offset, 10 * S + S // 1000)
    # taken 0.5 s after it came (a busy taker): it arrived 1 ms after it was sent
    sent = 11 * S + offset
    assert clocks.arrival("lidar", sent, 11 * S + S // 2) == sent + 2 * S + S // 1000


def test_a_sender_never_stamped_arrives_when_taken_and_never_later() -> None:
    clocks = SenderClocks()
    assert clocks.arrival("cam", 0, 5 * S) == 5 * S
    clocks.learn("cam", 0, 5 * S)  # a first message slow on its way: a large lag
    assert clocks.arrival("cam", S, S + 10) == S + 10  # taken sooner than that lag


def test_only_stamps_teach_the_lag_not_takes() -> None:
    clocks = SenderClocks()
    clocks.learn("lidar", 0, S // 1000)
    for t in range(1, 20):  # taken on a schedule, always 6 ms after they were sent
        assert clocks.arrival("lidar", t * S // 10, t * S // 10 + 6 * S // 1000) == (
            t * S // 10 + S // 1000
        )


def test_a_clock_that_steps_back_is_believed_again() -> None:
    clocks = SenderClocks()
    for t in range(10):  # 1 ms on the way, the sender's clock right
        clocks.learn("base", t * S, t * S + S // 1000)
    # the sender's clock steps 1 s back: at first its messages seem 1 s old ...
    clocks.learn("base", 10 * S - S, 10 * S)
    assert clocks.arrival("base", 10 * S - S, 10 * S) == 10 * S - S + S // 1000
    # ... for at most two spans, then they arrive when stamped
    for t in range(11, 10 + 2 * SPAN // S + 2):
        clocks.learn("base", t * S - S, t * S)
    assert clocks.arrival("base", t * S - S, t * S + S) == t * S


def test_the_senders_kept_are_bounded() -> None:
    clocks = SenderClocks()
    for n in range(SENDERS + 10):
        clocks.learn(f"s{n}", 0, S)
    assert len(clocks._lags) == SENDERS
    assert "s0" not in clocks._lags and f"s{SENDERS + 9}" in clocks._lags


class HeldBus(Bus):
    """A bus whose subscription handlers wait while ``free`` is clear (a busy process)."""

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        self.free = threading.Event()
        self.free.set()

    def subscribe(self, key: str, handler: Handler, *, decoded: bool = True) -> Any:
        def held(message: Message) -> None:
            self.free.wait()
            handler(message)

        return super().subscribe(key, held, decoded=decoded)


@pytest.fixture
def bus(endpoint: str) -> Iterator[HeldBus]:
    with HeldBus("testbot", name="executive", endpoint=endpoint, listen=True) as opened:
        yield opened


@pytest.fixture
def sender(bus: HeldBus) -> Iterator[Bus]:
    with Bus("testbot", name="lidar", endpoint=bus.endpoint) as opened:
        yield opened


@pytest.fixture
def recorder(bus: HeldBus) -> Iterator[list[Message]]:
    """What another process (not busy) receives on topic/data."""
    seen: list[Message] = []
    with Bus("testbot", name="recorder", endpoint=bus.endpoint) as other:
        other.subscribe("topic/data", seen.append)
        yield seen


def send(sender: Bus, recorder: list[Message], numbers: range) -> None:
    """Publish ``{"i": n}`` for each n, once topic/data has all its subscribers; return
    once the recorder got them."""
    assert sender.wait_for_subscriber("topic/data")
    for i in numbers:
        sender.publish("topic/data", {"i": i})
    assert wait_for(lambda: len(recorder) >= numbers.stop)


def test_a_message_arrived_when_python_saw_it_not_when_it_was_taken(
    bus: HeldBus, sender: Bus, recorder: list[Message]
) -> None:
    polled = bus.poll("topic/data")
    send(sender, recorder, range(1))
    assert wait_for(lambda: bool(polled._stamps))  # stamped on its own thread
    time.sleep(0.2)  # a taker that comes later
    taken = time.time_ns()
    [message] = polled.drain()
    assert message.payload["i"] == 0
    assert message.received_ns < taken - 100_000_000  # not when taken
    polled.undeclare()


def test_messages_taken_before_python_saw_them_arrive_in_order_at_their_senders_lag(
    bus: HeldBus, sender: Bus, recorder: list[Message]
) -> None:
    polled = bus.poll("topic/data")
    send(sender, recorder, range(1))  # its lag is learnt ...
    assert wait_for(lambda: bool(polled._stamps))
    polled.drain()
    bus.free.clear()  # ... then the process is busy: nothing is stamped
    try:
        before = time.time_ns()
        send(sender, recorder, range(1, 6))
        time.sleep(0.2)
        taken = time.time_ns()
        messages = polled.drain()
    finally:
        bus.free.set()
    assert [m.payload["i"] for m in messages] == [1, 2, 3, 4, 5]
    assert all(before <= m.received_ns < taken - 100_000_000 for m in messages)
    assert wait_for(lambda: len(polled._stamps) == 5)  # the held stamps come late ...
    polled.drain()
    polled.drain()
    assert polled._stamps == {}  # ... and are forgotten
    polled.undeclare()


def test_the_stamps_of_a_subscription_nobody_takes_are_bounded(
    bus: HeldBus, sender: Bus, recorder: list[Message]
) -> None:
    polled = bus.poll("topic/data", capacity=4)
    send(sender, recorder, range(10))
    assert wait_for(lambda: len(polled._stamps) == 4)
    assert [m.payload["i"] for m in polled.drain()] == [6, 7, 8, 9]  # the latest
    polled.undeclare()
