"""Planning benchmark: time per engine on the example domains, oversubscription and
deadline strategies, and (phase 2) the executive's planning latencies.

Run: ``.venv/bin/python -m tests.benchmarks.planning [--repeats N]``. Times are wall
clock in dura's process for a warm worker (problem construction, search, validation
and conversion to the partial order included), p50/p95 over the repeats.
"""

from __future__ import annotations

import argparse
import functools
import statistics
import tempfile
import time
import warnings
from collections.abc import Callable
from pathlib import Path
from typing import Any

from executive.cli.output import section, table
from executive.planning.expression import Signature, parse
from executive.planning.goals import GoalSpec
from executive.planning.oversubscription import plan_goals
from executive.planning.planner import Planner, PlanningTask, PlanResult, engine_names
from executive.planning.problem import build, read_world
from executive.testing.harness import RobotProcess, robot_variant
from knowledge.domain import parse as parse_domain
from knowledge.domain import read_domain

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


def latency_table(repeats: int, tmp: Path) -> None:
    """The real executive (``dura run``) with the use case: event stamps of its KB log."""
    description = robot_variant(
        ROOT / "examples/usecase/robot.yaml",
        tmp / "usecase",
        {"behaviors": {"move_to": {"max_restarts": 0}}},
    )
    submitted: list[float] = []
    replanned: list[float] = []
    with RobotProcess(description, tmp / "run") as robot:
        places = ["dock", "lab"]  # the robot starts at the dock
        for i in range(repeats):
            here = places[i % 2]
            there = places[(i + 1) % 2]
            after = _last_id(robot)
            began = time.time()
            goal = robot.submit_goal(f"(robot_at {there})")
            dispatched = _next(robot, "DISPATCH", after)
            submitted.append(dispatched["stamp"] - began)
            # the behavior crashes: its task fails, the plan fails, a new plan is dispatched
            _next(robot, "START", after)
            robot.inject_fault("move_to", "crash")
            failed = _next(robot, "FAIL", after)
            again = _next(robot, "DISPATCH", int(failed["id"]))
            replanned.append(again["stamp"] - failed["stamp"])
            robot.wait_for(goal, "achieved", timeout=60)
            assert f"(robot_at {there})" in robot.facts("robot_at"), here
    rows = []
    for label, target, samples in (
        ("goal submitted -> first task dispatched", "250 ms", submitted),
        ("task failed -> replanned task dispatched", "150 ms", replanned),
    ):
        p50, p95 = percentiles(samples)
        rows.append([label, target, ms(p50), ms(p95), len(samples)])
    section(f"executive latencies (use case, dura run, kairos, {repeats} repeats)")
    table(["latency", "target p50", "p50 ms", "p95 ms", "n"], rows)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--repeats", type=int, default=10)
    parser.add_argument(
        "--only-latencies", action="store_true", help="only the executive's latencies"
    )
    args = parser.parse_args()
    with tempfile.TemporaryDirectory(prefix="dura-bench-") as tmp:
        tempfile.tempdir = tmp  # Aries, run in this process below, leaves its logs here
        if args.only_latencies:
            latency_table(args.repeats, Path(tmp))
            return
        try:
            engines_table(args.repeats, Path(tmp))
            oversubscription_table(args.repeats)
            deadline_table(args.repeats)
        finally:
            tempfile.tempdir = None
        latency_table(args.repeats, Path(tmp))


if __name__ == "__main__":
    main()
