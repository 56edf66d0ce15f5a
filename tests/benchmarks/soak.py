"""Soak: N goals one after another on a real executive of the use case; what grows.

    python -m tests.benchmarks.soak [--goals N | --minutes M] [--every SECONDS]
                                    [--warm-up N] [--time-scale S] [--heaptrack RECORD]

Each goal sends the robot to another place, ``(robot_at lab)``, ``(robot_at office)``,
``(robot_at dock)`` in turn, and waits until it is achieved; nothing is injected. With
``--every`` a goal after the warm-up is sent at most that often (the issue's robot takes
one every ~10 s; without it, and in the warm-up, one right after another); with
``--minutes`` goals are sent until that time has passed after the warm-up, instead of
``--goals``. After the warm-up, the executive's process (and its planner worker,
measured apart) is sampled after every goal: resident memory (and how much of it is
anonymous: the heap, not mapped files), threads, open files, and the knowledge base's
size (its file: the WAL beside it is bounded by SQLite's checkpoints).
The table gives each at the end of the warm-up and at the end, and the growth per goal;
false repairs are the faults counted and the repair rules fired with nothing injected
(0 is the only right answer). The executive's resident memory is also shown along the
run, its growth per goal in each half of it (a plateau: the second half's is near 0)
and its trend over all samples (a least-squares slope: the first and last samples hold
whatever memory was in use at that moment, the trend is not swayed by one sample), and
the machine's load average (the machine may be shared: a high
load may cost observers their rates). The executive also tells what its heap holds
(:mod:`tests.benchmarks.heap_probe`): malloc's bytes in use and kept free, SQLite's
memory and Python's objects, so that a growing RSS can be told apart from memory the
executive keeps. A soak that saw a false repair (or was stopped) keeps its folder (the
knowledge base and the components' logs), to be read afterwards; a soak that ended well
removes it.
With ``--heaptrack`` the executive runs under heaptrack, whose record
:mod:`tests.benchmarks.heaptrack_growth` reads: the blocks it holds, what grows and who
asked for it.
"""

from __future__ import annotations

import argparse
import contextlib
import itertools
import os
import shutil
import tempfile
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import psutil

from executive.testing.client import GoalEnded
from executive.testing.harness import RobotProcess
from tests.benchmarks import heap_probe, heaptrack_growth
from tests.conftest import USECASE

PLACES = ("lab", "office", "dock")
HEAP_ROWS = (  # what heap_probe tells, as the table names it, and its shift to the unit
    ("in_use", "  C heap in use (KiB)", 10),
    ("free", "  C heap free, kept (KiB)", 10),
    ("sqlite", "  of it in use, SQLite's (KiB)", 10),
    ("blocks", "Python objects (blocks)", 0),
)


@dataclass
class Sample:
    goals: int
    rss: int
    anonymous: int  # of rss: the heap's pages (Python's arenas, malloc's), not mapped files
    worker_rss: int
    threads: int
    files: int
    kb: int
    load: float
    heap: dict[str, int]  # what the executive's heap holds (heap_probe), if it could tell


def sample(robot: RobotProcess, goals: int, probe: Path) -> Sample:
    process = psutil.Process(robot.pid)
    workers = [c for c in process.children(recursive=True) if _is_worker(c)]
    kb = robot.kb_path.stat().st_size  # its WAL is bounded by SQLite's checkpoints
    return Sample(
        goals,
        process.memory_info().rss,
        _anonymous(robot.pid),
        sum(_rss(w) for w in workers),
        process.num_threads(),
        process.num_fds(),
        kb,
        os.getloadavg()[0],
        heap_probe.latest(probe),
    )


def _anonymous(pid: int) -> int:
    """The process's anonymous resident memory in bytes (Linux's smaps_rollup)."""
    for line in Path(f"/proc/{pid}/smaps_rollup").read_text().splitlines():
        if line.startswith("Anonymous:"):
            return int(line.split()[1]) << 10
    return 0


def _is_worker(process: psutil.Process) -> bool:
    try:
        return "worker" in " ".join(process.cmdline())
    except psutil.Error:  # a component's process just ending
        return False


def _rss(process: psutil.Process) -> int:
    try:
        return int(process.memory_info().rss)
    except psutil.Error:
        return 0


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--goals", type=int, default=60, help="goals after the warm-up")
    parser.add_argument("--minutes", type=float,
                        help="send goals for this long after the warm-up instead")  # fmt: skip
    parser.add_argument("--every", type=float, default=0.0, help="seconds between goals")
    parser.add_argument("--warm-up", type=int, default=10, help="goals before measuring")
    parser.add_argument("--time-scale", type=float, default=10.0, help="robot time speed-up")
    parser.add_argument("--heaptrack", type=Path, help="record the executive's heap here (.zst)")
    args = parser.parse_args()
    began = time.monotonic()
    folder = Path(tempfile.mkdtemp(prefix="dura-soak-"))
    probe = folder / "heap.jsonl"
    os.environ.update(heap_probe.install(folder / "probe", probe))  # the executive's
    traced = heaptrack_growth.recording(args.heaptrack) if args.heaptrack else None
    with (
        traced or contextlib.nullcontext(),
        RobotProcess(USECASE, folder / "robot", time_scale=args.time_scale) as robot,
    ):
        samples, missed = _soak(robot, args, probe)
        repairs = [f"{e.kind} {e.subject}: {e.data.get('reason', e.data.get('faulty', ''))}"
                   for kind in ("FAULT", "RULE_FIRED") for e in robot.events(kind)]  # fmt: skip
    if repairs:  # its knowledge base and logs tell what the observers saw
        print(f"kept {folder} (false repairs: read its knowledge base with dura)")
    else:
        shutil.rmtree(folder)
    loads = [s.load for s in samples]
    print(f"{samples[-1].goals - samples[0].goals} goals after a warm-up of {args.warm_up}, "
          f"time scale {args.time_scale:g}, {time.monotonic() - began:.0f} s, load average "
          f"{sum(loads) / len(loads):.1f} (at most {max(loads):.1f})")  # fmt: skip
    _report(samples, missed, repairs)


def _soak(robot: RobotProcess, args: argparse.Namespace, probe: Path) -> tuple[list[Sample], int]:
    """Send the goals; the samples after the warm-up, and how many goals were missed."""
    samples: list[Sample] = []
    places = itertools.cycle(PLACES)
    missed = 0
    until: float | None = None  # with --minutes: set once the warm-up is done
    for n in itertools.count(1):
        if not args.minutes and n > args.warm_up + args.goals:
            break
        if until is not None and time.monotonic() >= until and n > args.warm_up + 1:
            break
        sent = time.monotonic()
        goal = robot.submit_goal(f"(robot_at {next(places)})")
        try:
            robot.wait_for(goal, timeout=120)
        except GoalEnded:  # e.g. an integrity goal after a false repair came first
            missed += 1
        if n >= args.warm_up:
            samples.append(sample(robot, n, probe))
        if n == max(1, args.warm_up) and args.minutes:
            until = time.monotonic() + args.minutes * 60
        if n >= args.warm_up:  # the warm-up only fills what fills up: as fast as it goes
            time.sleep(max(0.0, sent + args.every - time.monotonic()))
    return samples, missed


def _report(samples: list[Sample], missed: int, repairs: list[str]) -> None:
    first, last = samples[0], samples[-1]
    count = max(1, last.goals - first.goals)
    rows = [
        ("executive RSS (KiB)", first.rss >> 10, last.rss >> 10),
        ("  of it anonymous (KiB)", first.anonymous >> 10, last.anonymous >> 10),
    ]
    rows += [(name, first.heap[key] >> shift, last.heap[key] >> shift)
             for key, name, shift in HEAP_ROWS
             if key in first.heap and key in last.heap]  # fmt: skip
    rows += [
        ("planner worker RSS (KiB)", first.worker_rss >> 10, last.worker_rss >> 10),
        ("threads", first.threads, last.threads),
        ("open files", first.files, last.files),
        ("knowledge base (KiB)", first.kb >> 10, last.kb >> 10),
    ]
    faults = sum(r.startswith("FAULT") for r in repairs)
    fired = len(repairs) - faults
    print(f"{'what':<30} {'after warm-up':>14} {'at the end':>12} {'per goal':>10}")
    for name, before, after in rows:
        print(f"{name:<30} {before:>14} {after:>12} {(after - before) / count:>+10.2f}")
    print(f"{'false repairs':<30} {'':>14} {faults + fired:>12}  ({faults} faults, "
          f"{fired} rules fired)")  # fmt: skip
    print(f"{'goals not achieved':<30} {'':>14} {missed:>12}")
    tenth = max(1, len(samples) // 10)
    trend = ", ".join(f"{s.goals}: {s.rss >> 10}" for s in samples[::tenth])
    print(f"executive RSS (KiB) along the run, after goal N: {trend}")
    middle = samples[len(samples) // 2]
    halves = [_slope(a, b) for a, b in ((first, middle), (middle, last))]
    print(f"executive RSS per goal: {halves[0]} in the first half, {halves[1]} in the second")
    trends: list[tuple[str, Callable[[Sample], int]]] = [
        ("RSS", lambda s: s.rss),
        ("anonymous", lambda s: s.anonymous),
    ]
    trends += [(name.strip().removesuffix(" (KiB)"), _heap(key))
               for key, name, shift in HEAP_ROWS
               if shift == 10 and all(key in s.heap for s in samples)]  # fmt: skip
    slopes = ", ".join(f"{name} {_trend(samples, value) / 1024:+.2f}" for name, value in trends)
    print(f"executive trend (least squares over all {len(samples)} samples, which one "
          f"sample's ups and downs do not sway), KiB per goal: {slopes}")  # fmt: skip
    for repair in repairs[:10]:
        print(f"  {repair}")


def _heap(key: str) -> Callable[[Sample], int]:
    return lambda s: s.heap.get(key, 0)


def _trend(samples: list[Sample], value: Callable[[Sample], int]) -> float:
    """The least-squares slope of ``value`` over the goals of ``samples``, per goal."""
    return heaptrack_growth.trend([s.goals for s in samples], [value(s) for s in samples])


def _slope(a: Sample, b: Sample) -> str:
    """The executive's RSS growth per goal from sample ``a`` to ``b``."""
    return f"{((b.rss - a.rss) >> 10) / max(1, b.goals - a.goals):+.2f} KiB (goals {a.goals}-{b.goals})"


if __name__ == "__main__":
    main()
