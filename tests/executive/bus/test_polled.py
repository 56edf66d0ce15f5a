"""Each sender's clock seen from the taker (executive.bus.polled.SenderClocks)."""

from __future__ import annotations

from executive.bus.polled import SENDERS, SPAN, SenderClocks

S = 1_000_000_000  # a second in ns


def test_a_late_take_does_not_make_a_message_late() -> None:
    clocks = SenderClocks()
    offset = -2 * S  # the sender's clock is 2 s behind; the transport takes 1 ms
    assert clocks.arrival("lidar", 10 * S + offset, 10 * S + S // 1000) == 10 * S + S // 1000
    # taken 0.5 s after it came (a busy taker): it arrived 1 ms after it was sent
    sent = 11 * S + offset
    assert clocks.arrival("lidar", sent, 11 * S + S // 2) == sent + 2 * S + S // 1000


def test_never_later_than_taken() -> None:
    clocks = SenderClocks()
    clocks.arrival("cam", 0, 5 * S)  # a first message slow on its way: a large lag
    assert clocks.arrival("cam", S, S + 10) == S + 10  # a faster one: its own lag


def test_a_clock_that_steps_back_is_believed_again() -> None:
    clocks = SenderClocks()
    for t in range(10):  # 1 ms on the way, the sender's clock right
        clocks.arrival("base", t * S, t * S + S // 1000)
    # the sender's clock steps 1 s back: at first its messages seem 1 s old ...
    assert clocks.arrival("base", 10 * S - S, 10 * S) == 10 * S - S + S // 1000
    # ... for at most two spans, then they arrive when taken
    for t in range(11, 10 + 2 * SPAN // S + 2):
        last = clocks.arrival("base", t * S - S, t * S)
    assert last == t * S


def test_the_senders_kept_are_bounded() -> None:
    clocks = SenderClocks()
    for n in range(SENDERS + 10):
        clocks.arrival(f"s{n}", 0, S)
    assert len(clocks._lags) == SENDERS
    assert "s0" not in clocks._lags and f"s{SENDERS + 9}" in clocks._lags
