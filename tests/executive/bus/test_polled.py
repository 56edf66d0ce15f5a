"""Each sender's clock seen from the taker (executive.bus.polled.SenderClocks)."""

from __future__ import annotations

from executive.bus.polled import FORGET, SENDERS, SenderClocks

S = 1_000_000_000  # a second in ns


def test_a_late_take_does_not_make_a_message_late() -> None:
    clocks = SenderClocks()
    offset = -2 * S  # the sender's clock is 2 s behind; the transport takes 1 ms
    assert clocks.arrival("lidar", 10 * S + offset, 10 * S + S // 1000) == 10 * S + S // 1000
    # taken 0.5 s after it came (a busy taker): it arrived 1 ms after it was sent (and
    # what was forgotten of the least lag in the 1.5 s since)
    sent = 11 * S + offset
    forgotten = round((S + S // 2 - S // 1000) * FORGET)  # since the first was taken
    assert clocks.arrival("lidar", sent, 11 * S + S // 2) == sent + 2 * S + S // 1000 + forgotten


def test_never_later_than_taken() -> None:
    clocks = SenderClocks()
    clocks.arrival("cam", 0, 5 * S)  # a first message slow on its way: a large lag
    assert clocks.arrival("cam", S, S + 10) == S + 10  # a faster one: its own lag


def test_a_clock_that_steps_back_is_believed_again() -> None:
    clocks = SenderClocks()
    for t in range(10):  # 1 ms on the way, the sender's clock right
        clocks.arrival("base", t * S, t * S + S // 1000)
    # the sender's clock steps 1 s back: at first its messages seem 1 s old ...
    first = clocks.arrival("base", 10 * S - S, 10 * S)
    assert first < 10 * S - S + S // 50
    # ... and the least lag is forgotten at FORGET, until its messages arrive when taken
    later = 10 * S + round(1.1 * S / FORGET)
    assert clocks.arrival("base", later - S, later) == later


def test_the_senders_kept_are_bounded() -> None:
    clocks = SenderClocks()
    for n in range(SENDERS + 10):
        clocks.arrival(f"s{n}", 0, S)
    assert len(clocks._least) == SENDERS
    assert "s0" not in clocks._least and f"s{SENDERS + 9}" in clocks._least
