"""What the executive's heap holds, told by the executive itself: for the soak benchmark.

Resident memory alone does not say whether a process keeps more and more, or whether
its C library's ``malloc`` keeps freed memory it cannot give back (free chunks between
chunks in use, on pages that stay resident). :func:`install` makes the Python processes
that a benchmark starts run :func:`watch` from a ``sitecustomize`` module; in the
executive (``python -m executive.cli run``) it writes a line of JSON every few seconds:

- ``in_use``: bytes that ``malloc`` handed out and nobody freed yet (Zenoh, clingo,
  SQLite and Python's larger objects), and ``free``: bytes it holds free
  (glibc's ``mallinfo2``);
- ``sqlite``: SQLite's own memory, mostly its page cache (bounded by ``cache_size``,
  2 MiB by default);
- ``blocks``: Python's objects (its allocated blocks).

:func:`latest` reads the newest line. With another C library (or SQLite built into
Python) the figures it cannot get are absent.
"""

from __future__ import annotations

import ctypes
import functools
import json
import os
import sys
import threading
import time
from pathlib import Path

EVERY = 5.0  # seconds between two lines
_VARIABLE = "DURA_HEAP_PROBE"
_ROOT = Path(__file__).resolve().parents[2]  # the tree that holds tests/


class _MallInfo2(ctypes.Structure):
    _fields_ = [  # glibc's struct mallinfo2, in its order
        (name, ctypes.c_size_t)
        for name in (
            "arena",
            "ordblks",
            "smblks",
            "hblks",
            "hblkhd",
            "usmblks",
            "fsmblks",
            "uordblks",
            "fordblks",
            "keepcost",
        )
    ]


def install(folder: Path, out: Path) -> dict[str, str]:
    """The environment that makes the executive started with it write to ``out``
    (a ``sitecustomize`` module in ``folder``, first on its path)."""
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "sitecustomize.py").write_text(
        f"import sys\nsys.path.append({str(_ROOT)!r})\n"
        "from tests.benchmarks.heap_probe import watch\nwatch()\n"
    )
    path = os.pathsep.join(p for p in (str(folder), os.environ.get("PYTHONPATH", "")) if p)
    return {"PYTHONPATH": path, _VARIABLE: str(out)}


def watch() -> None:
    """In the executive (once its arguments are known), write a line every ``EVERY``
    seconds on a thread of its own; elsewhere nothing."""
    out = os.environ.get(_VARIABLE)
    if out:
        threading.Thread(target=_write, args=(Path(out),), daemon=True, name="heap-probe").start()


def _write(out: Path) -> None:
    time.sleep(1.0)  # sys.argv is the module's once ``-m`` has found it
    if not sys.argv[0].endswith(os.path.join("executive", "cli", "__main__.py")):
        return
    if "run" not in sys.argv[1:2]:
        return
    sqlite: ctypes.CDLL | None = None
    with out.open("a") as file:
        while True:
            sqlite = sqlite or _sqlite()  # looked for until the executive has loaded it
            file.write(json.dumps(_figures(sqlite)) + "\n")
            file.flush()
            time.sleep(EVERY)


@functools.cache
def _libc() -> ctypes.CDLL | None:
    try:
        libc = ctypes.CDLL("libc.so.6")
        libc.mallinfo2.restype = _MallInfo2
    except (OSError, AttributeError):
        return None
    return libc


def malloc() -> tuple[int, int] | None:
    """The bytes glibc's ``malloc`` handed out and did not have back (in its arenas and
    mapped on their own), and the bytes it keeps free; ``None`` with another C library."""
    libc = _libc()
    if libc is None:
        return None
    info = libc.mallinfo2()
    return int(info.uordblks + info.hblkhd), int(info.fordblks)


def _sqlite() -> ctypes.CDLL | None:
    """SQLite's shared library, once Python's ``sqlite3`` module has loaded it (not a
    copy of its own)."""
    try:
        if "libsqlite3" not in Path("/proc/self/maps").read_text():
            return None
        return ctypes.CDLL("libsqlite3.so.0")
    except OSError:
        return None


def _figures(sqlite: ctypes.CDLL | None) -> dict[str, int]:
    figures = {"blocks": sys.getallocatedblocks()}
    heap = malloc()
    if heap is not None:
        figures["in_use"], figures["free"] = heap
    now, peak = ctypes.c_int64(), ctypes.c_int64()
    if (
        sqlite is not None
        and sqlite.sqlite3_status64(0, ctypes.byref(now), ctypes.byref(peak), 0) == 0
    ):
        figures["sqlite"] = now.value  # SQLITE_STATUS_MEMORY_USED
    return figures


def latest(out: Path) -> dict[str, int]:
    """The newest figures written to ``out`` ({} before the first): its last lines only."""
    try:
        with out.open("rb") as file:
            file.seek(max(0, file.seek(0, os.SEEK_END) - 4096))
            lines = file.read().decode(errors="replace").splitlines()
    except FileNotFoundError:
        return {}
    for line in reversed(lines):
        try:
            figures = json.loads(line)
        except ValueError:  # a line being written, or cut by the seek
            continue
        return {k: int(v) for k, v in figures.items()}
    return {}
