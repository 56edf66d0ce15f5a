"""Benchmark of the command line: what a quick command costs, beside a bare Python.

    python -m tests.benchmarks.cli [--runs N] [--validate-runs N]

Starts the use-case robot (a real ``dura run``) and runs, in its folder, ``python -c
pass`` (the baseline), ``dura status``, ``dura goal list``, ``dura component list``
and ``dura validate`` of the use case, round-robin so that every command sees the same
machine. Twice: quiet, and loaded (a second process spinning on another core). For
each command it prints the median CPU time of the child process (user + sys) and its
ratio to the baseline measured in the same run, the median wall time, and the limits
of issue 19: a quick command at most 80 ms of CPU and 2.5 times the baseline;
``dura validate`` at most 1 s (wall). Bytecode caches are written before measuring, as
an installed dura has them. It also lists any solver, planner or graph library a quick
command imports (``python -X importtime``), and any other module beyond
:data:`QUICK_IMPORTS`: there should be none. The tricks that keep the quick commands
quick are in :mod:`executive.fast_start`.
"""

from __future__ import annotations

import argparse
import os
import re
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from collections.abc import Iterable, Iterator, Sequence
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path

from executive.testing.harness import RobotProcess
from tests.conftest import ROOT, USECASE

QUICK = (("status",), ("goal", "list"), ("component", "list"))
QUICK_CPU_MS = 80.0
QUICK_RATIO = 2.5
VALIDATE_WALL_MS = 1000.0
HEAVY = ("clingo", "unified_planning", "up_kairos", "up_aries", "up_fast_downward",
         "networkx", "starlette", "uvicorn", "cyclonedds", "numpy", "scipy")  # fmt: skip
# What a quick command may import besides dura's own modules and what a bare Python
# imports as it starts, by top-level name (a private helper such as _json goes with its
# module): the standard library's modules it needs, and Zenoh. Anything else slows every
# quick command (``inspect``, ``copy``, ``shutil``, ``logging``, ``yaml``...): measure it
# with this benchmark before adding it here.
QUICK_IMPORTS = frozenset(
    ("argparse", "atexit", "collections", "contextlib", "copyreg", "dataclasses", "enum",
     "errno", "fnmatch", "functools", "gc", "genericpath", "gettext", "importlib",
     "ipaddress", "itertools", "json", "keyword", "locale", "math", "ntpath", "operator",
     "os", "pathlib", "posixpath", "re", "reprlib", "runpy", "signal", "stat", "threading",
     "types", "typing", "urllib", "warnings", "zenoh")
)  # fmt: skip
DURA = ("executive", "knowledge", "monitoring")


@dataclass
class Samples:
    """CPU (user + sys of the child) and wall times of one command, in milliseconds."""

    cpu: list[float] = field(default_factory=list)
    wall: list[float] = field(default_factory=list)


def environment() -> dict[str, str]:
    env = {k: v for k, v in os.environ.items() if k != "PYTHONDONTWRITEBYTECODE"}
    return {**env, "PYTHONPATH": str(ROOT)}


def dura_command() -> list[str]:
    """The ``dura`` console script beside this interpreter (what a user runs), else
    ``python -m executive.cli``."""
    script = Path(sys.executable).with_name("dura")
    return [str(script)] if script.exists() else [sys.executable, "-m", "executive.cli"]


def measure(argv: Sequence[str], cwd: Path, env: dict[str, str], into: Samples) -> None:
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    began = time.perf_counter()
    done = subprocess.run(argv, cwd=cwd, env=env, capture_output=True, check=False)
    wall = time.perf_counter() - began
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if done.returncode != 0:
        raise SystemExit(f"{' '.join(argv)} failed:\n{done.stderr.decode(errors='replace')}")
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    into.cpu.append(cpu * 1000)
    into.wall.append(wall * 1000)


def commands(dura: list[str]) -> dict[str, list[str]]:
    quick = {f"dura {' '.join(c)}": [*dura, *c] for c in QUICK}
    return {"python -c pass": [sys.executable, "-c", "pass"], **quick}


def run_condition(
    folder: Path, runs: int, validate_runs: int
) -> tuple[dict[str, Samples], Samples]:
    env, dura = environment(), dura_command()
    argvs = commands(dura)
    validate = [*dura, "validate", str(USECASE)]
    for argv in [*argvs.values(), validate]:  # warm up: bytecode caches, page cache
        measure(argv, folder, env, Samples())
    samples = {name: Samples() for name in argvs}
    for _ in range(runs):
        for name, argv in argvs.items():
            measure(argv, folder, env, samples[name])
    validated = Samples()
    for _ in range(validate_runs):
        measure(validate, folder, env, validated)
    return samples, validated


@contextmanager
def load(on: bool) -> Iterator[None]:
    """A second process spinning on a core while the block runs (if ``on``)."""
    if not on:
        yield
        return
    spinner = subprocess.Popen([sys.executable, "-c", "while True: pass"])
    try:
        time.sleep(0.5)
        yield
    finally:
        spinner.kill()
        spinner.wait()


def imported(argv: Sequence[str], folder: Path, env: dict[str, str]) -> set[str]:
    """The modules a Python command imports (``python -X importtime``, then ``argv``)."""
    done = subprocess.run(
        [sys.executable, "-X", "importtime", *argv],
        cwd=folder, env=env, capture_output=True, text=True, check=False,
    )  # fmt: skip
    return set(re.findall(r"^import time: +\d+ \| +\d+ \| +(\S+)$", done.stderr, re.MULTILINE))


def unlisted(modules: Iterable[str], bare: Iterable[str]) -> list[str]:
    """The top-level names among ``modules`` that are none of dura's, none that a bare
    Python imports (``bare``: its modules) and not in :data:`QUICK_IMPORTS`."""
    allowed = QUICK_IMPORTS | {m.split(".")[0] for m in bare}
    tops = {m.split(".")[0] for m in modules}
    return sorted(t for t in tops if t not in allowed and t not in DURA and t[0] != "_")


def quick_imports(folder: Path) -> dict[str, tuple[list[str], list[str]]]:
    """For each quick command, the solver, planner and graph modules it imports, and
    the modules beyond :data:`QUICK_IMPORTS` (both should be empty)."""
    env = environment()
    bare = imported(["-c", "pass"], folder, env)
    found: dict[str, tuple[list[str], list[str]]] = {}
    for command in QUICK:
        names = imported(["-m", "executive.cli", *command], folder, env)
        heavy = sorted({n for n in names if n.split(".")[0] in HEAVY})
        found[" ".join(command)] = (heavy, unlisted(names, bare))
    return found


def report(condition: str, samples: dict[str, Samples], validated: Samples) -> list[str]:
    base = statistics.median(samples["python -c pass"].cpu)
    rows = []
    for name, s in samples.items():
        cpu, wall = statistics.median(s.cpu), statistics.median(s.wall)
        if name == "python -c pass":
            limit, ok = "(baseline)", ""
        else:
            limit = f"<= {QUICK_CPU_MS:g} ms, <= {QUICK_RATIO:g}x"
            ok = "yes" if cpu <= QUICK_CPU_MS and cpu <= QUICK_RATIO * base else "NO"
        rows.append((condition, name, len(s.cpu), cpu, cpu / base, wall, limit, ok))
    cpu, wall = statistics.median(validated.cpu), statistics.median(validated.wall)
    ok = "yes" if wall <= VALIDATE_WALL_MS else "NO"
    rows.append(
        (condition, "dura validate (use case)", len(validated.cpu), cpu, cpu / base, wall,
         f"wall <= {VALIDATE_WALL_MS:g} ms", ok)
    )  # fmt: skip
    return [
        f"{c:<7} {n:<26} {k:>4} {cpu:>8.1f} {ratio:>6.2f}x {wall:>8.1f}  {limit:<20} {ok}"
        for c, n, k, cpu, ratio, wall, limit, ok in rows
    ]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=30, help="runs of each quick command")
    parser.add_argument("--validate-runs", type=int, default=5, help="runs of dura validate")
    args = parser.parse_args()
    os.environ["PYTHONPATH"] = str(ROOT)  # the executive and its components run this tree
    lines = []
    with tempfile.TemporaryDirectory() as tmp, RobotProcess(USECASE, Path(tmp) / "robot") as robot:
        for condition in ("quiet", "loaded"):
            with load(condition == "loaded"):
                measured = run_condition(robot.folder, args.runs, args.validate_runs)
            lines += report(condition, *measured)
        imports = quick_imports(robot.folder)
    print(f"{os.cpu_count()} cores, load average {os.getloadavg()[0]:.2f} at the end; "
          f"dura as {' '.join(dura_command())}")  # fmt: skip
    print(f"{'load':<7} {'command':<26} {'runs':>4} {'CPU ms':>8} {'ratio':>7} {'wall ms':>8}"
          f"  {'limit':<20} ok")  # fmt: skip
    for line in lines:
        print(line)
    for command, (heavy, beyond) in imports.items():
        print(f"dura {command}: solver, planner or graph imports: {', '.join(heavy) or 'none'}; "
              f"beyond QUICK_IMPORTS: {', '.join(beyond) or 'none'}")  # fmt: skip


if __name__ == "__main__":
    main()
