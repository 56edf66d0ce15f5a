"""Benchmark of fleets: how soon a goal reaches a robot, and how soon a lost robot's work
starts again elsewhere, for fleets of 2, 5 and 10 robots beside one robot alone.

    python -m tests.benchmarks.fleet [--sizes 1 2 5 10] [--samples N] [--scale S]

Each robot is the example's (``examples/fleet/r1.yaml`` renamed; simulated hardware),
run by its own ``dura run`` process with its own bus login, beside the fleet's ``dura
fleet run``; the depot's problem is made for the fleet's size (a dock per robot, a
store, a lab, a parcel per sample). Two figures, each over ``--samples`` runs:

- **goal → step**: from ``dura goal add`` (the fleet's verb) to the first step of the
  plan started on its robot (the fleet's ``START`` event: the robot's task executor
  reported it running). Planning for more robots costs the planner more.
- **lost → restarted**: from the SIGKILL of the executive of the robot whose step runs
  to the next step started on another robot (liveliness lost, step failed, robot set
  aside, new plan, its first step started). With one robot there is no other: the row
  "1" restarts that robot's executive at once and measures until its step starts
  again there (recovery by restart, the baseline a fleet improves on).

It prints p50 and p95 (of few samples: p95 is near the worst) per size, in seconds of
wall time, with the robot time scale it ran at.
"""

from __future__ import annotations

import argparse
import contextlib
import statistics
import tempfile
import time
from collections.abc import Iterator, Sequence
from pathlib import Path

from executive.testing.fleet import FleetProcess, fleet_variant
from executive.testing.harness import RobotProcess, robot_variant
from knowledge.records import Event
from tests.conftest import ROOT

EXAMPLE = ROOT / "examples" / "fleet"


def problem(count: int, parcels: int) -> str:
    """The depot for ``count`` robots: a dock each, a store with the parcels, a lab."""
    robots = [f"r{i}" for i in range(1, count + 1)]
    docks = [f"dock{i}" for i in range(1, count + 1)]
    crates = [f"parcel{i}" for i in range(1, parcels + 1)]
    init = [f"(at {r} {d}) (hands_free {r}) (= (battery {r}) 100)"
            for r, d in zip(robots, docks, strict=True)]  # fmt: skip
    init += [f"(road {d} store) (road store {d})" for d in docks]
    init += ["(road store lab) (road lab store) (road store office) (road office store)"]
    init += [f"(crate_at {c} store)" for c in crates]
    return (
        f"(define (problem depot-{count}) (:domain depot)\n"
        f"  (:objects {' '.join(robots)} - robot {' '.join(docks)} store lab office - place\n"
        f"            {' '.join(crates)} - crate)\n"
        f"  (:init {' '.join(init)})\n  (:goal (and)))\n"
    )


@contextlib.contextmanager
def fleet_of(
    count: int, parcels: int, folder: Path, scale: float
) -> Iterator[tuple[FleetProcess, dict[str, RobotProcess]]]:
    """``count`` robots' executives and the fleet's process, in ``folder``."""
    with contextlib.ExitStack() as stack:
        robots: dict[str, RobotProcess] = {}
        for i in range(1, count + 1):
            name = f"r{i}"
            description = robot_variant(EXAMPLE / "r1.yaml", folder / "descriptions" / name,
                                        {"robot": name})  # fmt: skip
            description = description.rename(description.with_name(f"{name}.yaml"))
            robots[name] = stack.enter_context(
                RobotProcess(description, folder / name, time_scale=scale)
            )
        made = folder / "problem.pddl"
        made.write_text(problem(count, parcels))
        description = fleet_variant(EXAMPLE / "fleet.yaml", list(robots.values()), folder,
                                    problem=str(made))  # fmt: skip
        fleet = stack.enter_context(
            FleetProcess(description, folder / "fleet", time_scale=scale, join_wait=60.0)
        )
        yield fleet, robots


def newest(fleet: FleetProcess) -> int:
    events = fleet.events(limit=1)
    return events[-1].id if events else 0


def started(fleet: FleetProcess, after: int, unlike: str = "") -> Event:
    """The first step started after event ``after`` (by a robot other than ``unlike``)."""
    while True:
        event = fleet.wait_for_event("START", after=after, timeout=120)
        if event.data.get("robot") and event.data.get("robot") != unlike:
            return event
        after = event.id


def measure(count: int, samples: int, scale: float) -> tuple[list[float], list[float]]:
    """The goal → step and lost → restarted latencies of a fleet of ``count`` robots."""
    to_step: list[float] = []
    restarted: list[float] = []
    with (
        tempfile.TemporaryDirectory(prefix=f"dura-fleet-{count}-") as folder,
        fleet_of(count, 2 * samples, Path(folder), scale) as (fleet, robots),
    ):
        parcel = 0
        for _ in range(samples):
            parcel += 1
            after = newest(fleet)
            began = time.time()
            goal = fleet.submit_goal(f"(crate_at parcel{parcel} lab)")
            to_step.append(started(fleet, after).stamp - began)
            fleet.wait_for(goal, "achieved", timeout=180)
        for _ in range(samples):
            parcel += 1
            after = newest(fleet)
            goal = fleet.submit_goal(f"(crate_at parcel{parcel} lab)")
            first = started(fleet, after)
            victim = str(first.data["robot"])
            began = time.time()
            robots[victim].kill()
            if count == 1:  # no other robot: the executive restarts, the step with it
                robots[victim].start()
                restarted.append(started(fleet, first.id).stamp - began)
            else:
                restarted.append(started(fleet, first.id, unlike=victim).stamp - began)
                robots[victim].start()
            fleet.wait_for(goal, "achieved", timeout=180)
            all_back(fleet)
    return to_step, restarted


def all_back(fleet: FleetProcess, timeout: float = 60.0) -> None:
    """Wait until every robot of the fleet can act again (a restarted one has joined)."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        robots = fleet.status().robots
        if isinstance(robots, list) and all(r.available for r in robots):
            return
        time.sleep(0.2)


def percentile(values: Sequence[float], q: float) -> float:
    ordered = sorted(values)
    return ordered[min(len(ordered) - 1, round(q * (len(ordered) - 1)))]


def main(argv: Sequence[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", type=int, nargs="+", default=[1, 2, 5, 10])
    parser.add_argument("--samples", type=int, default=5)
    parser.add_argument("--scale", type=float, default=10.0, help="robot time scale (10)")
    args = parser.parse_args(argv)
    rows = []
    for count in args.sizes:
        to_step, restarted = measure(count, args.samples, args.scale)
        rows.append((count, to_step, restarted))
        print(f"{count} robots: done", flush=True)
    print(f"\nfleet latencies, seconds of wall time (robot time x{args.scale:g}, "
          f"{args.samples} samples each)")  # fmt: skip
    print(f"{'robots':>6}  {'goal->step p50':>14}  {'p95':>6}  {'lost->restarted p50':>19}  "
          f"{'p95':>6}")  # fmt: skip
    for count, to_step, restarted in rows:
        print(f"{count:>6}  {statistics.median(to_step):>14.2f}  {percentile(to_step, 0.95):>6.2f}"
              f"  {statistics.median(restarted):>19.2f}  {percentile(restarted, 0.95):>6.2f}"
              + ("  (one robot: its executive restarted)" if count == 1 else ""))  # fmt: skip


if __name__ == "__main__":
    main()
