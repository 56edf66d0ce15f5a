"""Planning benchmark: time per engine on the example domains, oversubscription and
deadline strategies, and the high level's speed (issue 19).

Run: ``.venv/bin/python -m tests.benchmarks.planning [--repeats N] [--speed]``. Engine
times are wall clock in dura's process for a warm worker (problem construction, search,
validation and conversion to the partial order included), p50/p95 over the repeats.

The speed table (``--speed`` for it alone) measures each figure quiet and with a second
process keeping one core busy, beside a baseline of the same run: ``dura run`` until
``status`` answers (and until its planner is warm) beside ``python -c pass``; goal
submitted -> first dispatch and task failure -> new dispatch of a real ``dura run``
(event stamps of its log) beside the planner alone (a warm worker called from here, for
the same goal); the worker's job, search and validation with its caches beside the
uncached path (the problem's kind recomputed at every look, a validator made per plan).
"""

from __future__ import annotations

import argparse
import contextlib
import functools
import json
import os
import signal
import statistics
import subprocess
import sys
import tempfile
import time
import warnings
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

from executive.bus import security
from executive.bus.api import planning as api
from executive.bus.session import Bus
from executive.cli.output import section, table
from executive.planning.expression import Signature, parse
from executive.planning.goals import GoalSpec
from executive.planning.oversubscription import plan_goals
from executive.planning.planner import Planner, PlanningTask, PlanResult, engine_names
from executive.planning.problem import build, read_world
from executive.testing.harness import RobotProcess, free_endpoint, robot_variant
from knowledge.domain import parse as parse_domain
from knowledge.domain import read_domain
from knowledge.errors import BusError

ROOT = Path(__file__).resolve().parents[2]
USECASE = (ROOT / "domains/usecase/domain.pddl", ROOT / "examples/usecase/problem.pddl")
TRANSPORT = (ROOT / "domains/transport/domain.pddl", ROOT / "examples/transport/problem.pddl")
ROOMS_DOMAIN = """(define (domain rooms) (:requirements :strips :typing) (:types room)
  (:predicates (at ?r - room) (door ?a ?b - room) (visited ?r - room))
  (:action go :parameters (?a ?b - room) :precondition (and (at ?a) (door ?a ?b))
    :effect (and (not (at ?a)) (at ?b) (visited ?b))))"""
ROOMS_PROBLEM = """(define (problem tour) (:domain rooms) (:objects a b c d e - room)
  (:init (at a) (door a b) (door b c) (door c d) (door d e) (door e a) (door c a))
  (:goal (and (visited e) (visited c) (at a))))"""

CASES = {
    "usecase: 2 pictures, dock": (
        USECASE,
        ["(picture_taken lab)", "(picture_taken office)", "(robot_at dock)"],
    ),
    "transport: parcel to lab, dock": (TRANSPORT, ["(crate_at parcel lab)", "(robot_at dock)"]),
}


def percentiles(samples: list[float]) -> tuple[float, float]:
    ordered = sorted(samples)
    p95 = ordered[min(len(ordered) - 1, round(0.95 * (len(ordered) - 1)))]
    return statistics.median(ordered), p95


def ms(seconds: float) -> str:
    return f"{seconds * 1000:.0f}"


def task_for(
    files: tuple[Path, Path],
    goals: list[str],
    deadlines: dict[int, float] | None = None,
    priorities: dict[int, int] | None = None,
) -> PlanningTask:
    domain, problem = files
    world, _ = read_world(domain, problem)
    sig = Signature.of(read_domain(domain), world.objects)
    specs = tuple(
        GoalSpec(i, parse(g, sig), (priorities or {}).get(i, 0), (deadlines or {}).get(i))
        for i, g in enumerate(goals, 1)
    )
    return PlanningTask(domain, world, specs)


def measure(run: Callable[[], PlanResult | None], repeats: int) -> tuple[list[float], str]:
    samples: list[float] = []
    status = ""
    for _ in range(repeats):
        began = time.perf_counter()
        result = run()
        samples.append(time.perf_counter() - began)
        status = "-" if result is None else result.status.value
    return samples, status


def engines_table(repeats: int, tmp: Path) -> None:
    rooms_domain, rooms_problem = tmp / "rooms.pddl", tmp / "tour.pddl"
    rooms_domain.write_text(ROOMS_DOMAIN)
    rooms_problem.write_text(ROOMS_PROBLEM)
    world, goal = read_world(rooms_domain, rooms_problem)
    cases = {name: task_for(files, goals) for name, (files, goals) in CASES.items()}
    cases["rooms (classical): tour"] = PlanningTask(rooms_domain, world, (GoalSpec(1, goal),))
    rows = []
    for engine in engine_names():
        try:
            planner = Planner(engine, timeout=30)
        except Exception as e:
            rows.append([engine, "-", "-", "-", f"n/a: {e}"])
            continue
        with planner:
            for name, task in cases.items():
                first = planner.solve(task)  # warms the worker and the domain
                if not first.ok:
                    rows.append(
                        [engine, name, "-", "-", f"{first.status.value}: {first.reason[:60]}"]
                    )
                    continue
                samples, status = measure(functools.partial(planner.solve, task), repeats)
                p50, p95 = percentiles(samples)
                rows.append(
                    [
                        engine,
                        name,
                        ms(p50),
                        ms(p95),
                        f"{status}, {len(first.plan.steps) if first.plan else 0} steps",
                    ]
                )
    section(f"planning time per engine (warm worker, {repeats} repeats)")
    table(["engine", "case", "p50 ms", "p95 ms", "result"], rows)


def oversubscription_table(repeats: int) -> None:
    """Ours (greedy by priority) against UP's oversubscription meta-engine and Kairos'
    own oversubscription metric, on the use case with one unreachable goal."""
    import up_kairos
    from unified_planning.model import metrics
    from unified_planning.shortcuts import OneshotPlanner, get_environment

    warnings.simplefilter("ignore")
    get_environment().credits_stream = None
    up_kairos.register()
    goals = [
        "(picture_taken lab)",
        "(picture_taken dock)",
        "(picture_taken office)",
        "(robot_at dock)",
    ]
    priorities = {1: 4, 2: 3, 3: 2, 4: 1}
    task = task_for(USECASE, goals, priorities=priorities)
    rows = []
    with Planner("kairos", timeout=10) as planner:
        plan_goals(planner, task)
        samples, _ = measure(lambda: plan_goals(planner, task).result, repeats)
        outcome = plan_goals(planner, task)
        p50, p95 = percentiles(samples)
        rows.append(
            [
                "dura: greedy by priority (worker)",
                ms(p50),
                ms(p95),
                f"goals {list(outcome.planned)}, {outcome.calls} calls, reasons for {list(outcome.unreachable)}",
            ]
        )
    # the two alternatives, in this process (no worker), for the same problem
    problem = build(parse_domain(USECASE[0]), task.world, ())
    fnodes = {g.id: build(parse_domain(USECASE[0]), task.world, (g,)).goals[0] for g in task.goals}
    gains = {fnodes[i]: 2 ** (len(goals) - i) for i in fnodes}  # lexicographic by priority
    problem.add_quality_metric(metrics.Oversubscription(gains))
    for name, engine in (
        ("UP oversubscription[kairos] meta-engine", "oversubscription[kairos]"),
        ("Kairos' own oversubscription metric", "kairos"),
    ):
        with OneshotPlanner(name=engine) as solver:
            samples = []
            answer = None
            for _ in range(repeats):
                began = time.perf_counter()
                answer = solver.solve(problem, timeout=10)
                samples.append(time.perf_counter() - began)
        p50, p95 = percentiles(samples)
        steps = (
            len(answer.plan.timed_actions) if answer is not None and answer.plan is not None else 0
        )
        rows.append(
            [
                f"{name} (in process)",
                ms(p50),
                ms(p95),
                f"{answer.status.name.lower() if answer else '-'}, {steps} steps, no reasons",
            ]
        )
    section("oversubscription: 4 goals, 1 unreachable (use case)")
    table(["strategy", "p50 ms", "p95 ms", "outcome"], rows)


def deadline_table(repeats: int) -> None:
    """Deadlines compiled to a timed-literal window (all engines) against UP's native
    timed goals (Aries only), on the transport domain."""
    from unified_planning import model
    from unified_planning.shortcuts import OneshotPlanner, get_environment

    warnings.simplefilter("ignore")
    get_environment().credits_stream = None
    rows = []
    plain = task_for(TRANSPORT, ["(crate_at parcel lab)", "(robot_at dock)"])
    timed = task_for(TRANSPORT, ["(crate_at parcel lab)", "(robot_at dock)"], deadlines={1: 30.0})
    for engine in ("kairos", "aries"):
        with Planner(engine, timeout=30) as planner:
            for label, task in (("no deadline", plain), ("deadline 30 s, compiled window", timed)):
                planner.solve(task)
                samples, status = measure(functools.partial(planner.solve, task), repeats)
                p50, p95 = percentiles(samples)
                rows.append([engine, label, ms(p50), ms(p95), status])
    problem = build(parse_domain(TRANSPORT[0]), plain.world, plain.goals)
    native = problem.clone()
    native.add_timed_goal(model.GlobalStartTiming(30), native.goals[0])
    with OneshotPlanner(name="aries") as aries:
        samples = []
        status = "-"
        for _ in range(repeats):
            began = time.perf_counter()
            status = aries.solve(native, timeout=30).status.name.lower()
            samples.append(time.perf_counter() - began)
    p50, p95 = percentiles(samples)
    rows.append(["aries", "UP timed goal at 30 s (in process)", ms(p50), ms(p95), status])
    section(f"deadlines (transport: parcel to lab by 30 s, {repeats} repeats)")
    table(["engine", "how", "p50 ms", "p95 ms", "result"], rows)


def _next(robot: RobotProcess, kind: str, after: int, timeout: float = 60.0) -> dict[str, Any]:
    """The first event of ``kind`` with an id above ``after``."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        for event in robot.request("events", {"after": after, "kind": kind, "limit": 1000})[
            "events"
        ]:
            return event
        time.sleep(0.01)
    raise TimeoutError(f"no {kind} event after #{after} within {timeout:g} s")


def _last_id(robot: RobotProcess) -> int:
    events = robot.request("events", {"limit": 1})["events"]
    return int(events[-1]["id"]) if events else 0


# --- the speed of the high level (issue 19): each figure beside a baseline of the same run


@contextlib.contextmanager
def loaded(on: bool) -> Iterator[None]:
    """With ``on``: a second process keeps one core busy meanwhile."""
    if not on:
        yield
        return
    spinner = subprocess.Popen([sys.executable, "-c", "while True: pass"])
    try:
        yield
    finally:
        spinner.kill()
        spinner.wait()


def _ready(robot_name: str, folder: Path, endpoint: str, began: float) -> tuple[float, float]:
    """Seconds from ``began`` until the executive answered ``status``, and until its
    planner was warm (the first goal would not wait)."""
    answered = None
    deadline = began + 120
    while time.monotonic() < deadline:
        try:
            login = security.find_login(robot_name, security.OPERATOR, [folder])
            with Bus(robot_name, name="bench", endpoint=endpoint, login=login) as bus:
                while time.monotonic() < deadline:
                    try:
                        status = api.STATUS.call(bus, timeout=0.5)
                    except BusError:
                        continue
                    if answered is None:
                        answered = time.monotonic() - began
                    if status.planning is None or not status.planning.starting:
                        return answered, time.monotonic() - began
                    time.sleep(0.005)
        except BusError:
            time.sleep(0.005)
    raise TimeoutError("the executive did not start")


def start_times(runs: int, tmp: Path) -> dict[str, list[float]]:
    """``dura run`` of the use case (a restart on its knowledge base) until ``status``
    answers and until the planner is warm; ``python -c pass`` as the baseline."""
    folder = tmp / "start"
    folder.mkdir(parents=True, exist_ok=True)
    description = ROOT / "examples/usecase/robot.yaml"
    out: dict[str, list[float]] = {"status": [], "warm": [], "python": []}
    for i in range(runs + 1):  # the first creates the credentials and the knowledge base
        endpoint = free_endpoint()
        log = folder / f"executive-{i}.log"
        began = time.monotonic()
        with log.open("w") as err:
            process = subprocess.Popen(
                [sys.executable, "-m", "executive.cli", "run", str(description), "--endpoint",
                 endpoint, "--db", str(folder / "usecase.db"), "--log-dir", str(folder / "logs")],
                cwd=folder, stdout=subprocess.DEVNULL, stderr=err,
                env={**os.environ, "PYTHONFAULTHANDLER": "1"},
            )  # fmt: skip
        try:
            answered, warm = _ready("usecase", folder, endpoint, began)
        finally:
            process.send_signal(signal.SIGTERM)
            try:
                process.wait(30)
            except subprocess.TimeoutExpired:
                process.send_signal(signal.SIGABRT)  # its threads' stacks into the log
                process.wait(10)
                raise RuntimeError(f"dura run did not stop within 30 s: see {log}") from None
        out["status"].append(answered)
        out["warm"].append(warm)
        began = time.monotonic()
        subprocess.run([sys.executable, "-c", "pass"], check=True)
        out["python"].append(time.monotonic() - began)
    return {k: v[1:] for k, v in out.items()}


def executive_latencies(runs: int, tmp: Path) -> dict[str, list[float]]:
    """The real executive (``dura run``) with the use case, from the event stamps of its
    log: goal submitted -> first dispatch, and a crashed behavior's FAIL -> the new
    plan's dispatch; the baseline is the planner alone (a warm worker, called from this
    process) for the same goal."""
    description = robot_variant(
        ROOT / "examples/usecase/robot.yaml",
        tmp / "usecase",
        {"behaviors": {"move_to": {"max_restarts": 0, "params": {"duration": 1.0}}}},
    )
    out: dict[str, list[float]] = {"submitted": [], "replanned": [], "planner": []}
    with RobotProcess(description, tmp / "run") as robot:
        _ready(robot.robot.name, robot.folder, robot.endpoint, time.monotonic())
        places = ["dock", "lab"]  # the robot starts at the dock
        for i in range(runs):
            there = places[(i + 1) % 2]
            after = _last_id(robot)
            began = time.time()
            goal = robot.submit_goal(f"(robot_at {there})")
            dispatched = _next(robot, "DISPATCH", after)
            out["submitted"].append(dispatched["stamp"] - began)
            # the behavior crashes: its task fails, the plan fails, a new plan is dispatched
            _next(robot, "START", after)
            robot.inject_fault("move_to", "crash")
            failed = _next(robot, "FAIL", after)
            again = _next(robot, "DISPATCH", int(failed["id"]))
            out["replanned"].append(again["stamp"] - failed["stamp"])
            robot.wait_for(goal, "achieved", timeout=60)
    task = task_for(USECASE, ["(robot_at lab)"])
    with Planner("kairos", timeout=30) as planner:
        planner.start(USECASE[0])
        for _ in range(runs):
            began = time.monotonic()
            planner.solve(task)
            out["planner"].append(time.monotonic() - began)
    return out


def worker_times(runs: int) -> dict[str, list[float]]:
    """The planner worker's job with what it caches and without, each in a fresh process
    (UP's factory slows down with every validator it makes)."""
    out: dict[str, list[float]] = {}
    for mode in ("cached", "uncached"):
        done = subprocess.run(
            [sys.executable, "-m", "tests.benchmarks.planning", "--worker-job", mode,
             "--repeats", str(runs)],
            capture_output=True, text=True, check=True, cwd=ROOT,
        )  # fmt: skip
        for name, samples in json.loads(done.stdout.splitlines()[-1]).items():
            out[f"{name} {mode}"] = samples
    return out


def worker_job(runs: int, cached: bool) -> dict[str, list[float]]:
    """The planner worker's job in this process, with what it caches or without (as
    before: the problem's kind recomputed at every look, a validator made per plan)."""
    from executive.planning.planner_worker import warm_up

    worker = warm_up(Path(tempfile.gettempdir()) / "engine-output.txt")  # as the worker does
    from executive.planning.planner_jobs import _missing_features, _validate
    from executive.planning.problem import frozen
    from executive.planning.stn import partial_order

    task = task_for(USECASE, ["(picture_taken lab)", "(robot_at office)"])
    engine = worker.engine("kairos")
    out: dict[str, list[float]] = {"search": [], "validation": [], "job": []}

    def uncached_validator(name: str) -> Any:
        from unified_planning.shortcuts import PlanValidator

        return PlanValidator(name=name)

    for i in range(runs + 3):
        began = time.perf_counter()
        problem = build(worker.domain(task.domain), task.world, task.goals)
        if cached:
            problem = frozen(problem)
        _missing_features(engine, problem)
        searched = time.perf_counter()
        answer = engine.solve(problem, timeout=30)
        validated = time.perf_counter()
        valid = _validate(problem, answer.plan, worker.validator if cached else uncached_validator)
        assert valid[0], valid
        converted = time.perf_counter()
        partial_order(problem, answer.plan)
        ended = time.perf_counter()
        if i >= 3:  # after a warm-up
            out["search"].append(validated - searched)
            out["validation"].append(converted - validated)
            out["job"].append(ended - began)
    return out


def speed_table(runs: int, tmp: Path) -> None:
    """Issue 19's figures of the high level, quiet and with a second process loading
    the other core, each beside its baseline measured in the same run."""
    results: dict[bool, dict[str, list[float]]] = {}
    for busy in (False, True):
        with loaded(busy):
            found = start_times(max(3, runs // 2), tmp / f"start-{busy}")
            found.update(executive_latencies(runs, tmp / f"latency-{busy}"))
            found.update(worker_times(runs))
        results[busy] = found
    figures = [
        ("dura run -> status answers", "500 ms quiet", "status", "python -c pass", "python"),
        ("dura run -> planner warm", "-", "warm", "python -c pass", "python"),
        ("goal -> first dispatch", "100 ms p95 loaded", "submitted", "planner alone", "planner"),
        ("failure -> new dispatch", "100 ms p95 loaded", "replanned", "planner alone", "planner"),
        ("worker job (build..convert)", "-", "job cached", "uncached", "job uncached"),
        ("search (kairos)", "-", "search cached", "uncached", "search uncached"),
        ("validation (kairos-val)", "-", "validation cached", "uncached", "validation uncached"),
    ]
    rows = []
    for label, target, key, baseline, base_key in figures:
        row: list[Any] = [label, target]
        for busy in (False, True):
            p50, p95 = percentiles(results[busy][key])
            b50, _ = percentiles(results[busy][base_key])
            row += [ms(p50), ms(p95), f"{ms(b50)} ({p50 / b50:.1f}x)"]
        rows.append([*row, baseline])
    load = os.getloadavg()[0]
    section(
        f"high level speed (use case, kairos; {runs} goals and failures, "
        f"{max(3, runs // 2)} starts; load average {load:.1f} on {os.cpu_count()} cores)"
    )
    table(
        ["figure", "target", "quiet p50", "p95", "baseline p50 (ratio)",
         "loaded p50", "p95", "baseline p50 (ratio)", "baseline"],
        rows,
    )  # fmt: skip


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--repeats", type=int, default=10)
    parser.add_argument(
        "--speed",
        "--only-latencies",
        action="store_true",
        help="only the high level's speed: start, goal and failure to dispatch, the worker",
    )
    parser.add_argument("--worker-job", choices=["cached", "uncached"], help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.worker_job:
        warnings.simplefilter("ignore")
        print(json.dumps(worker_job(args.repeats, args.worker_job == "cached")))
        return
    with tempfile.TemporaryDirectory(prefix="dura-bench-") as tmp:
        tempfile.tempdir = tmp  # Aries, run in this process below, leaves its logs here
        if args.speed:
            speed_table(args.repeats, Path(tmp))
            return
        try:
            engines_table(args.repeats, Path(tmp))
            oversubscription_table(args.repeats)
            deadline_table(args.repeats)
            speed_table(args.repeats, Path(tmp))
        finally:
            tempfile.tempdir = None


if __name__ == "__main__":
    main()
