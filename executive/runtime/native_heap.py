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

glibc also keeps a cache of freed blocks for each thread (up to seven of each size up to
1 KiB), which no other thread can use and no trim gives back. The executive has many
threads that live as long as it does (zenoh-python runs each subscription's handler on
a Python thread of its own: about sixty), and each one's cache fills slowly with the
sizes it happens to free: in soaks of the use case after 330 goals, the blocks in use
(``heaptrack``) stayed flat while malloc's count of bytes in use grew by 0.69 and 3.75
KiB per goal, and by -0.15 and +0.19 with the caches off.
:func:`restart_without_thread_caches` starts ``dura run`` again in its own process with
them off (glibc reads its tunables only when a program starts), unless
``GLIBC_TUNABLES`` already names ``glibc.malloc.tcache_count``; the processes it starts
get the environment as it was.
"""

from __future__ import annotations

import ctypes
import ctypes.util
import functools
import os
import sys
import threading
from collections.abc import Mapping
from typing import Any

ARENAS = 2  # malloc arenas of a dura process (glibc's default: eight per core)
TRIM_EVERY = 30.0  # seconds between two trims of the heap
_M_ARENA_MAX = -8  # mallopt's parameter number (glibc's malloc.h)
TUNABLES = "GLIBC_TUNABLES"
NO_THREAD_CACHES = "glibc.malloc.tcache_count=0"
# in the program started again: GLIBC_TUNABLES as it was ("=" and its value; "" if unset)
_RESTARTED = "DURA_GLIBC_TUNABLES"


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


def without_thread_caches(environ: Mapping[str, str]) -> dict[str, str] | None:
    """The environment to start this program again with, glibc's caches of freed blocks
    per thread off; ``None`` if there is nothing to do (not glibc, the caches are already
    set in ``GLIBC_TUNABLES``, or this is the process started again)."""
    if _glibc() is None or _RESTARTED in environ:
        return None
    tunables = environ.get(TUNABLES)
    if tunables is not None and "glibc.malloc.tcache_count" in tunables:
        return None  # the user's choice
    return {
        **environ,
        TUNABLES: f"{tunables}:{NO_THREAD_CACHES}" if tunables else NO_THREAD_CACHES,
        _RESTARTED: "" if tunables is None else f"={tunables}",
    }


def restart_without_thread_caches() -> None:
    """Start this program again in the same process (same PID, arguments and open files)
    with glibc's caches of freed blocks per thread off, and return in the program started
    again, its environment as it was before (so that what it starts gets that). Call it
    first thing, before anything is opened or started; nothing happens where
    :func:`without_thread_caches` says so, or when the program cannot be started again."""
    environment = without_thread_caches(os.environ)
    if environment is None:
        _restore()
        return
    if not sys.executable:
        return
    for stream in (sys.stdout, sys.stderr):
        if stream is not None:
            stream.flush()
    try:
        os.execve(sys.executable, sys.orig_argv, environment)  # noqa: S606 - this very program
    except OSError:
        return


def _restore() -> None:
    """In the program started again: ``GLIBC_TUNABLES`` as it was before."""
    before = os.environ.pop(_RESTARTED, None)
    if before is None:
        return
    if before.startswith("="):
        os.environ[TUNABLES] = before[1:]
    else:
        os.environ.pop(TUNABLES, None)


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
