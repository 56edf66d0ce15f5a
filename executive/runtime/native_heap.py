"""The C heap of a long-running dura process: few malloc arenas, free pages given back.

Zenoh's threads and clingo allocate with the C library's ``malloc``. glibc gives threads
arenas of their own, up to eight per core, and memory freed in one arena serves only the
threads of that arena. A component that logs in to the bus and leaves again makes the
router allocate on several of Zenoh's threads at once and free nearly all of it later,
but the free chunks stay spread over many arenas, and the executive's resident memory
grows with every component start. A router of dura's bus, 800 component logins four at
a time: with all arenas its heap grew by 1.6 MB from login 200 to 800 and kept growing;
limited to two, it stopped growing after login 400 (``tests.benchmarks.bus_logins``
measures the like).

:func:`limit_arenas` caps the arenas (what ``MALLOC_ARENA_MAX`` does; that variable, if
set, wins): call it first thing in a process, before any thread starts. A
:class:`HeapTrimmer` gives the free pages of every arena back to the system now and then
(``malloc_trim``), so that the resident memory shows what is in use. With another C
library (musl, macOS) both do nothing.
"""

from __future__ import annotations

import ctypes
import ctypes.util
import functools
import os
import threading
from typing import Any

ARENAS = 2  # malloc arenas of a dura process (glibc's default: eight per core)
TRIM_EVERY = 30.0  # seconds between two trims of the heap
_M_ARENA_MAX = -8  # mallopt's parameter number (glibc's malloc.h)


@functools.cache
def _glibc() -> Any | None:
    """glibc, if this process's C library is glibc (loaded once)."""
    try:
        libc = ctypes.CDLL(ctypes.util.find_library("c") or "libc.so.6")
        libc.gnu_get_libc_version  # noqa: B018  (glibc alone has it)
        libc.mallopt  # noqa: B018
        libc.malloc_trim  # noqa: B018
    except (OSError, AttributeError):
        return None
    return libc


def limit_arenas(arenas: int = ARENAS) -> bool:
    """Cap glibc's malloc arenas at ``arenas``, unless ``MALLOC_ARENA_MAX`` says otherwise;
    whether the cap was set. Threads that already have an arena keep it: call this
    before any thread starts."""
    libc = _glibc()
    if libc is None or "MALLOC_ARENA_MAX" in os.environ:
        return False
    return bool(libc.mallopt(_M_ARENA_MAX, arenas))


def trim() -> bool:
    """Give the heap's free pages back to the system; whether any were."""
    libc = _glibc()
    return bool(libc is not None and libc.malloc_trim(0))


class HeapTrimmer:
    """Trims the heap every ``every`` seconds on a thread of its own, until closed."""

    def __init__(self, every: float = TRIM_EVERY) -> None:
        self._every = every
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, daemon=True, name="heap-trim")
        if _glibc() is not None:
            self._thread.start()

    def _run(self) -> None:
        while not self._stop.wait(self._every):
            trim()  # ctypes lets go of the GIL during the call: the other threads go on

    def close(self) -> None:
        self._stop.set()
        if self._thread.is_alive():
            self._thread.join()

    def __enter__(self) -> HeapTrimmer:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
