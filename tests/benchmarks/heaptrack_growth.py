"""The blocks a process holds over time, from heaptrack's record: what grows, by whom.

    python -m tests.benchmarks.heaptrack_growth RECORD.zst [--from S] [--to S] [--top N]

heaptrack (Debian's package) records every block ``malloc`` hands out and every one
freed, with its backtrace. :func:`recording` makes the executive that a benchmark starts
(``python -m tests.benchmarks.soak --heaptrack RECORD``) run with heaptrack's preload
library, and the executive alone: heaptrack clears its variables for the processes the
executive starts. The executive runs with glibc's thread caches off, as ``dura run``
sets them, but without starting itself again (that would leave the record behind).

This script reads a record: the bytes in blocks not yet freed along the run, and
between ``--from`` and ``--to`` (seconds after the executive started) their trend in
all, by the library that asked for them (the first frame outside the C library and
heaptrack) and by backtrace, the largest first. A process that keeps nothing more has
a trend near 0 whatever its resident memory does.
"""

from __future__ import annotations

import argparse
import contextlib
import os
import shutil
import statistics
import subprocess
import sys
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path

PRELOAD = Path("/usr/lib/heaptrack/libheaptrack_preload.so")
INTERPRET = Path("/usr/lib/heaptrack/libexec/heaptrack_interpret")
SNAPSHOT = 10_000  # milliseconds between two counts of the blocks not yet freed
ALLOCATORS = ("libc.so", "libheaptrack", "libstdc++", "ld-linux")  # not who asked


@contextlib.contextmanager
def recording(record: Path) -> Iterator[None]:
    """Within: the executive that :class:`~executive.testing.harness.RobotProcess`
    starts runs under heaptrack, its record written to ``record`` (zstd)."""
    if not (PRELOAD.exists() and INTERPRET.exists() and shutil.which("zstd")):
        raise SystemExit("heaptrack and zstd are needed (Debian: apt install heaptrack zstd)")
    record.parent.mkdir(parents=True, exist_ok=True)
    fifo = record.with_name(record.name + ".fifo")
    wrapper = record.with_name(record.name + ".python")
    fifo.unlink(missing_ok=True)
    os.mkfifo(fifo)
    wrapper.write_text(
        "#!/bin/sh\n"
        f"LD_PRELOAD={PRELOAD} DUMP_HEAPTRACK_OUTPUT={fifo} "
        f'GLIBC_TUNABLES=glibc.malloc.tcache_count=0 exec {sys.executable} "$@"\n'
    )
    wrapper.chmod(0o755)
    writer = subprocess.Popen(  # noqa: S602 - our own paths, quoted by nobody
        f"{INTERPRET} < {fifo} | zstd -q -c > {record}", shell=True
    )
    python, sys.executable = sys.executable, str(wrapper)  # the harness starts it
    try:
        yield
    finally:
        sys.executable = python
        writer.wait()
        fifo.unlink()
        wrapper.unlink()


@dataclass
class Record:
    strings: list[str] = field(default_factory=lambda: [""])
    frames: list[tuple[str, str]] = field(default_factory=lambda: [("", "")])  # module, function
    traces: list[tuple[int, int]] = field(default_factory=lambda: [(0, 0)])  # frame, parent
    snapshots: list[tuple[float, dict[int, int]]] = field(default_factory=list)  # s, trace: bytes

    def backtrace(self, trace: int) -> list[tuple[str, str]]:
        out = []
        while trace:
            frame, trace = self.traces[trace]
            out.append(self.frames[frame])
        return out

    def owner(self, trace: int) -> str:
        return next((m for m, _ in self.backtrace(trace) if not m.startswith(ALLOCATORS)), "?")


def read(path: Path) -> Record:
    """The record's blocks not yet freed, per backtrace, every :data:`SNAPSHOT` ms
    (heaptrack's interpreted format: one line per string, frame, trace, block kind,
    allocation, free and time stamp; numbers in hexadecimal)."""
    record = Record()
    kinds: list[tuple[int, int]] = []  # size, trace
    alive: list[int] = []
    due = SNAPSHOT
    with subprocess.Popen(["zstd", "-dc", str(path)], stdout=subprocess.PIPE) as unzip:
        assert unzip.stdout is not None
        for line in unzip.stdout:
            tag = line[:1]
            if tag == b"+":
                alive[int(line[2:], 16)] += 1
            elif tag == b"-":
                alive[int(line[2:], 16)] -= 1
            elif tag == b"a":
                _, size, trace = line.split()
                kinds.append((int(size, 16), int(trace, 16)))
                alive.append(0)
            elif tag == b"t":
                _, frame, parent = line.split()
                record.traces.append((int(frame, 16), int(parent, 16)))
            elif tag == b"i":
                numbers = [int(n, 16) for n in line.split()[1:]]
                function = record.strings[numbers[2]] if len(numbers) > 2 else hex(numbers[0])
                record.frames.append((os.path.basename(record.strings[numbers[1]]), function))
            elif tag == b"s":
                record.strings.append(
                    line.decode(errors="replace").rstrip("\n")[2:].partition(" ")[2]
                )
            elif tag == b"c" and int(line[2:], 16) >= due:
                now = int(line[2:], 16)
                held: dict[int, int] = {}
                for (size, trace), count in zip(kinds, alive, strict=True):
                    if count:
                        held[trace] = held.get(trace, 0) + count * size
                record.snapshots.append((now / 1000, held))
                due = now + SNAPSHOT
    return record


def trend(xs: list[float], ys: list[float]) -> float:
    """The least-squares slope of ``ys`` over ``xs`` (0 if the ``xs`` are all the same)."""
    if len(set(xs)) < 2:
        return 0.0
    return statistics.linear_regression(xs, ys).slope


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("record", type=Path, help="heaptrack's record (.zst)")
    parser.add_argument("--from", dest="start", type=float, default=0.0, help="seconds")
    parser.add_argument("--to", dest="end", type=float, default=float("inf"), help="seconds")
    parser.add_argument("--top", type=int, default=5, help="backtraces shown")
    args = parser.parse_args()
    record = read(args.record)
    window = [s for s in record.snapshots if args.start <= s[0] <= args.end]
    if len(window) < 3:
        raise SystemExit(f"{args.record}: fewer than 3 counts between the times given")
    times = [t for t, _ in window]
    span = times[-1] - times[0]
    along = ", ".join(
        f"{t:.0f} s: {sum(h.values()) >> 10}" for t, h in window[:: max(1, len(window) // 10)]
    )
    print(f"blocks not yet freed (KiB) along {times[0]:.0f}-{times[-1]:.0f} s: {along}")
    growth = {}
    for trace in set().union(*(h.keys() for _, h in window)):
        growth[trace] = trend(times, [h.get(trace, 0) for _, h in window]) * span
    total = trend(times, [sum(h.values()) for _, h in window]) * span
    print(f"trend over the window: {total / 1024:+.1f} KiB in all")
    owners: dict[str, float] = {}
    for trace, grown in growth.items():
        owner = record.owner(trace)
        owners[owner] = owners.get(owner, 0.0) + grown
    print(f"{'asked for by':<48} {'trend (KiB)':>12}")
    for owner, grown in sorted(owners.items(), key=lambda o: -abs(o[1]))[:8]:
        print(f"{owner:<48} {grown / 1024:>+12.1f}")
    for trace, grown in sorted(growth.items(), key=lambda g: -g[1])[: args.top]:
        held = window[-1][1].get(trace, 0) >> 10
        print(f"\n{grown / 1024:+.1f} KiB (now {held} KiB), from:")
        for module, function in record.backtrace(trace)[:12]:
            if not module.startswith(ALLOCATORS) and "_PyEval" not in function:
                print(f"    {module}: {function[:100]}")


if __name__ == "__main__":
    main()
