"""PDDL corpus benchmark: every problem of a folder of domains through ``dura plan
--offline`` beside the same engine called directly through unified-planning (issue 28).

Run: ``.venv/bin/python -m tests.benchmarks.pddl_corpus DIR [--engine E] [--timeout S]
[--limit N]``. DIR holds domain folders (searched at any depth): each has
``instances/instance-N.pddl`` and either one ``domain.pddl`` or
``domains/domain-N.pddl`` (one per instance), as in the IPC collections. The first
``--limit`` problems of each domain are run (by instance number).

For each problem, in the same run and one after the other: dura, as a user runs it
(``dura plan --offline --json``, its plan validated), and the engine called directly
(this module with ``--direct``: unified-planning's PDDL reader and ``OneshotPlanner`` of
the engine, ``auto``: UP's choice for the problem's kind; its plan validated afterwards,
out of its time). Both are whole processes under the same search timeout, so both times
include starting Python and loading unified-planning; the ratio is dura's time over the
direct one. The summary counts the problems parsed, solved and validly solved by each,
the median ratio over the problems both solved, and the problems the engine solves
directly but dura does not (what parity, issue 28 item 4, is about).

Third-party domains are read where they are, never copied into the repository.
"""

from __future__ import annotations

import argparse
import json
import re
import statistics
import subprocess
import sys
import time
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

from executive.cli.output import section, table

ROOT = Path(__file__).resolve().parents[2]
GRACE = 30.0  # seconds a process may take beyond its search timeout before it is killed


@dataclass(frozen=True)
class Outcome:
    """One run on one problem: ``status`` is parse_error, solved, or why not."""

    status: str
    time: float
    makespan: float | None = None
    valid: bool = False
    reason: str = ""

    @property
    def parsed(self) -> bool:
        return self.status != "parse_error"

    @property
    def solved(self) -> bool:
        return self.status == "solved"


def _number(path: Path) -> int:
    found = re.search(r"(\d+)", path.stem)
    return int(found.group(1)) if found else 0


def problems(folder: Path, limit: int, skip: int = 0) -> list[tuple[str, Path, Path]]:
    """(domain folder name, domain file, problem file) for the first ``limit`` instances of
    every domain folder under ``folder``, after the first ``skip``."""
    out: list[tuple[str, Path, Path]] = []
    for instances in sorted(folder.rglob("instances")):
        home = instances.parent
        for problem in sorted(instances.glob("*.pddl"), key=_number)[skip : skip + limit]:
            own = home / "domains" / f"domain-{_number(problem)}.pddl"
            domain = own if own.exists() else home / "domain.pddl"
            if domain.exists():
                name = str(home.relative_to(folder)) if home != folder else folder.name
                out.append((name, domain, problem))
    return out


def _last_line(text: str) -> str:
    lines = [line for line in text.splitlines() if line.strip()]
    return lines[-1].strip() if lines else ""


def run_dura(domain: Path, problem: Path, engine: str, timeout: float) -> Outcome:
    """``dura plan --offline --json``, as a user runs it."""
    argv = [sys.executable, "-m", "executive.cli", "plan", "--offline", str(domain), str(problem),
            "--engine", engine, "--timeout", f"{timeout:g}", "--json"]  # fmt: skip
    began = time.monotonic()
    try:
        done = subprocess.run(
            argv, capture_output=True, text=True, timeout=timeout + GRACE, cwd=ROOT, check=False
        )
    except subprocess.TimeoutExpired:
        return Outcome("killed", time.monotonic() - began)
    took = time.monotonic() - began
    try:
        answer = json.loads(done.stdout)
    except json.JSONDecodeError:
        return Outcome("parse_error", took, reason=_last_line(done.stderr))
    status = str(answer["status"])
    solved = status == "solved"
    return Outcome(status, took, answer.get("makespan"), solved, str(answer.get("reason", "")))


def run_direct(domain: Path, problem: Path, engine: str, timeout: float) -> Outcome:
    """The engine through unified-planning, in a process of its own."""
    argv = [sys.executable, "-m", "tests.benchmarks.pddl_corpus", "--direct", str(domain),
            str(problem), "--engine", engine, "--timeout", f"{timeout:g}"]  # fmt: skip
    began = time.monotonic()
    try:
        done = subprocess.run(
            argv, capture_output=True, text=True, timeout=timeout + GRACE, cwd=ROOT, check=False
        )
    except subprocess.TimeoutExpired:
        return Outcome("killed", time.monotonic() - began)
    try:
        answer = json.loads(_last_line(done.stdout))
    except json.JSONDecodeError:
        return Outcome("error", time.monotonic() - began, reason=_last_line(done.stderr))
    return Outcome(
        answer["status"],
        float(answer["time"]),
        answer.get("makespan"),
        bool(answer.get("valid")),
        answer.get("reason", ""),
    )


def direct(domain: Path, problem: Path, engine: str, timeout: float) -> dict[str, Any]:
    """Parse and solve with unified-planning alone (the time: from this process's start
    to the engine's answer); then validate the plan, out of that time."""
    import os
    import warnings

    import psutil

    warnings.simplefilter("ignore")
    started = psutil.Process(os.getpid()).create_time()
    import up_kairos
    from unified_planning.engines import ValidationResultStatus
    from unified_planning.io import PDDLReader
    from unified_planning.shortcuts import OneshotPlanner, PlanValidator, get_environment

    env = get_environment()
    env.credits_stream = None
    up_kairos.register(env)
    try:
        parsed = PDDLReader().parse_problem(str(domain), str(problem))
    except Exception as e:
        return {"status": "parse_error", "time": time.time() - started, "reason": str(e)[:200]}
    try:
        chosen = {"name": engine} if engine != "auto" else {"problem_kind": parsed.kind}
        with OneshotPlanner(**chosen) as planner:
            answer = planner.solve(parsed, timeout=timeout)
    except Exception as e:
        reason = f"{type(e).__name__}: {e}".splitlines()[0][:200]
        return {"status": "error", "time": time.time() - started, "reason": reason}
    took = time.time() - started
    name = answer.status.name
    if answer.plan is None or not name.startswith(("SOLVED", "INTERMEDIATE")):
        return {"status": name.lower(), "time": took}
    valid = False
    for validator in ("up_time_triggered_validator", "sequential_plan_validator", "kairos-val"):
        try:
            checker = PlanValidator(name=validator)
            if checker.supports(parsed.kind):
                valid = checker.validate(parsed, answer.plan).status == ValidationResultStatus.VALID
                break
        except Exception:  # noqa: S112 (a validator that cannot check this plan: the next)
            continue
    plan = answer.plan
    makespan = None
    if hasattr(plan, "timed_actions"):
        makespan = float(max((s + (d or 0) for s, _, d in plan.timed_actions), default=0))
    return {"status": "solved", "time": took, "makespan": makespan, "valid": valid}


def _cell(o: Outcome) -> list[str]:
    span = "-" if o.makespan is None else f"{o.makespan:g}"
    status = o.status + ("" if o.valid or not o.solved else " (INVALID)")
    return [status, span, f"{o.time:.1f}"]


def report(rows: list[tuple[str, str, Outcome, Outcome]], engine: str, timeout: float) -> None:
    section(f"PDDL corpus: dura plan --offline beside {engine} through unified-planning, "
            f"timeout {timeout:g} s")  # fmt: skip
    table(
        ["domain", "problem", "dura", "makespan", "s", engine, "makespan", "s", "ratio"],
        [
            [d, p, *_cell(a), *_cell(b), f"{a.time / b.time:.2f}" if a.solved and b.solved else "-"]
            for d, p, a, b in rows
        ],
    )
    both = [a.time / b.time for _, _, a, b in rows if a.solved and b.solved and b.time > 0]
    domains = {d for d, *_ in rows}
    section("summary")
    for who, pick in (("dura", 2), (f"{engine} directly", 3)):
        outs = [r[pick] for r in rows]
        assert all(isinstance(o, Outcome) for o in outs)
        parsed_domains = {r[0] for r in rows if r[pick].parsed}  # type: ignore[union-attr]
        print(
            f"{who}: domains parsed {len(parsed_domains)}/{len(domains)}, problems parsed "
            f"{sum(o.parsed for o in outs)}/{len(outs)}, solved {sum(o.solved for o in outs)}, "
            f"valid {sum(o.solved and o.valid for o in outs)}"
        )
    if both:
        print(f"time ratio dura/direct over {len(both)} problems both solved: median "
              f"{statistics.median(both):.2f}, max {max(both):.2f}")  # fmt: skip
    lost = [(d, p, a) for d, p, a, b in rows if b.solved and b.valid and not a.solved]
    print(f"solved validly directly but not by dura: {len(lost)}")
    for d, p, a in lost:
        print(f"  {d}/{p}: {a.status}: {a.reason[:160]}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("folder", type=Path, help="a folder of domain folders")
    parser.add_argument("problem", nargs="?", type=Path, help=argparse.SUPPRESS)
    parser.add_argument("--engine", default="kairos", help="the engine (default kairos)")
    parser.add_argument("--timeout", type=float, default=20.0, help="seconds per search")
    parser.add_argument("--limit", type=int, default=2, help="problems per domain (default 2)")
    parser.add_argument(
        "--skip", type=int, default=0, help="problems per domain to leave out first"
    )
    parser.add_argument("--rows", type=Path, help="also append each row to FILE (JSON lines)")
    parser.add_argument("--direct", action="store_true", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.direct:  # one direct run, in its own process: the folder is the domain file
        print(json.dumps(direct(args.folder, args.problem, args.engine, args.timeout)))
        return
    rows: list[tuple[str, str, Outcome, Outcome]] = []
    for name, domain, problem in problems(args.folder, args.limit, args.skip):
        ours = run_dura(domain, problem, args.engine, args.timeout)
        theirs = run_direct(domain, problem, args.engine, args.timeout)
        rows.append((name, problem.stem, ours, theirs))
        print(f"{name}/{problem.stem}: dura {ours.status} {ours.time:.1f} s, direct "
              f"{theirs.status} {theirs.time:.1f} s", file=sys.stderr, flush=True)  # fmt: skip
        if args.rows is not None:
            line = {"domain": name, "problem": problem.stem, "dura": asdict(ours),
                    "direct": asdict(theirs)}  # fmt: skip
            with args.rows.open("a", encoding="utf-8") as out:
                out.write(json.dumps(line) + "\n")
    report(rows, args.engine, args.timeout)


if __name__ == "__main__":
    main()
