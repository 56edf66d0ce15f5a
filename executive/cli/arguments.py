"""Argument types of the command line: a number out of range is a usage error (exit 2)
that says what is allowed, before anything is asked of anyone."""

from __future__ import annotations

import argparse
import math
from collections.abc import Callable
from pathlib import Path

LIMIT = 10**9  # no count, priority or number of seconds a person means is larger


def _number(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"'{text}' is not a number") from None
    if not math.isfinite(value):
        raise argparse.ArgumentTypeError(f"'{text}' is not a finite number")
    return value


def _whole(text: str) -> int:
    try:
        return int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"'{text}' is not a whole number") from None


def seconds(*, zero: bool = False) -> Callable[[str], float]:
    """A positive number of seconds (or zero, if allowed), at most ``LIMIT``."""

    def read(text: str) -> float:
        value = _number(text)
        if value < 0 or (value == 0 and not zero) or value > LIMIT:
            least = "0" if zero else "more than 0"
            raise argparse.ArgumentTypeError(
                f"must be {least} and at most {LIMIT} seconds, not {text}"
            )
        return value

    return read


def moment(text: str) -> float:
    """A time to come, as seconds since the epoch: ``14:00`` or ``14:00:30`` (today, local
    time), ``+90`` (seconds from now) or ``2026-11-27T14:00`` (local time)."""
    import datetime  # only for --at: not on a quick path
    import time

    now = time.time()
    if text.startswith("+"):
        return now + seconds()(text[1:])
    try:
        if "T" in text or "-" in text:
            when = datetime.datetime.fromisoformat(text)
        else:
            clock = datetime.time.fromisoformat(text)
            when = datetime.datetime.combine(datetime.date.today(), clock)
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"'{text}' is not a time: write 14:00, 14:00:30, +90 (seconds from now) or "
            "2026-11-27T14:00"
        ) from None
    at = when.timestamp()
    if at <= now:
        raise argparse.ArgumentTypeError(f"{text} has passed: give a time to come")
    return at


def count(text: str) -> int:
    """A whole number from 0 to ``LIMIT``."""
    value = _whole(text)
    if not 0 <= value <= LIMIT:
        raise argparse.ArgumentTypeError(f"must be a whole number from 0 to {LIMIT}, not {text}")
    return value


def identifier(text: str) -> int:
    """An id: a whole number from 1 to 2**63 - 1 (what the knowledge base counts in)."""
    value = _whole(text)
    if not 1 <= value < 2**63:
        raise argparse.ArgumentTypeError(f"must be an id (a whole number from 1), not {text}")
    return value


def priority(text: str) -> int:
    """A goal's priority: a whole number from -``LIMIT`` to ``LIMIT``."""
    value = _whole(text)
    if not -LIMIT <= value <= LIMIT:
        raise argparse.ArgumentTypeError(
            f"must be a whole number from -{LIMIT} to {LIMIT}, not {text}"
        )
    return value


def rate(text: str) -> float:
    """A positive rate in Hz, at most ``LIMIT``."""
    value = _number(text)
    if not 0 < value <= LIMIT:
        raise argparse.ArgumentTypeError(f"must be more than 0 and at most {LIMIT} Hz, not {text}")
    return value


def factor(text: str) -> float:
    """A positive factor (a speed-up), at most ``LIMIT``."""
    value = _number(text)
    if not 0 < value <= LIMIT:
        raise argparse.ArgumentTypeError(f"must be more than 0 and at most {LIMIT}, not {text}")
    return value


def megabytes(text: str) -> int:
    """A size in MiB (fractions allowed, at least 64 KiB), as bytes."""
    value = _number(text)
    if not 1 / 16 <= value <= 1 << 20:
        raise argparse.ArgumentTypeError(f"must be from 0.0625 to {1 << 20} MB, not {text}")
    return round(value * (1 << 20))


def event_kind(text: str) -> str:
    """A kind of event dura logs (any case): ``FAIL``, ``task_failed``."""
    from executive.bus.event_kinds import KINDS  # only for --kind: not on a quick path

    kind = text.upper()
    if kind not in KINDS:
        raise argparse.ArgumentTypeError(
            f"no event is of kind '{text}'; the kinds are: {', '.join(sorted(KINDS))}"
        )
    return kind


def add_launcher_options(parser: argparse.ArgumentParser, *, resources: str) -> None:
    """The options of a process that launches components (``dura run``, ``dura host``):
    where their logs go, how often their resources are published (``resources``: the
    help), and how long each gets to stop."""
    parser.add_argument(
        "--log-dir",
        type=Path,
        default=Path(".dura") / "logs",
        help="where component logs go (default .dura/logs)",
    )
    parser.add_argument(
        "--resource-rate", type=rate, default=1.0, metavar="HZ", help=f"{resources} (default 1)"
    )
    parser.add_argument(
        "--grace",
        type=seconds(),
        default=3.0,
        metavar="SECONDS",
        help="time a component gets to stop, before SIGTERM and again before SIGKILL (default 3)",
    )
