"""How a command that runs until Ctrl-C or SIGTERM waits for it.

CPython runs a signal's handler on the main thread, but the kernel may hand the signal
to any thread of the process (one of Zenoh's), and that does not wake a main thread
blocked on a lock: the signal would wait for whatever wakes the main thread next. So the
main thread waits in slices, and a pending handler runs within one.
"""

from __future__ import annotations

import signal
import threading

SIGNAL_POLL = 0.1  # seconds: the longest a pending Ctrl-C or SIGTERM waits for its handler


def stop_on_signals() -> threading.Event:
    """An event that Ctrl-C (SIGINT) and SIGTERM set."""
    stop = threading.Event()
    for signum in (signal.SIGINT, signal.SIGTERM):
        signal.signal(signum, lambda *_: stop.set())
    return stop


def wait(stop: threading.Event) -> None:
    """Wait until ``stop`` is set (on the main thread: signals' handlers run meanwhile)."""
    while not stop.wait(SIGNAL_POLL):
        pass
