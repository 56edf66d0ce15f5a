"""Benchmark of fleets: a goal to its first step, and a lost robot's work to another,
for fleets of 1 (the baseline), 2, 5 and 10 robots in the same run.

    python -m tests.benchmarks.fleet [--runs N] [--robots 1,2,5,10] [--scale S]

Each fleet is the example depot (``examples/fleet``) with N transport robots, each a
real executive (``dura run``) with its simulated components, on this machine, and the
fleet's high level (``dura fleet run``) beside them; robot time runs ``--scale`` times
as fast as the wall clock. Each run asks for one more parcel in the lab and times, in
milliseconds, from the fleet's event log:

- **goal -> first step**: from the goal's submission to the start of the first step of
  its plan on the robot the step names (the robot's task executor said it started);
- **lost -> restarted**: the executive of that robot is SIGKILLed at once, and the time
  runs to the start of a step of the goal's new plan on another robot. With one robot
  there is no other: its executive is started again at once, and the time runs to its
  step restarted on it once it is back (the baseline a fleet improves on).

The killed robot is started again before the next run, and the run waits until the
goal is achieved, so each run starts with every robot there and idle. The load average
(1 minute) is printed before and after each fleet: 10 robots are 10 executives and 40
component processes on this machine.
"""

from __future__ import annotations

import argparse
import contextlib
import os
import tempfile
import time
from collections.abc import Iterator, Sequence
from dataclasses import dataclass, field
from pathlib import Path

from executive.cli.demo_fleet import EXAMPLE, start_robots
from executive.testing.fleet import FleetProcess, fleet_variant
from executive.testing.harness import RobotProcess, robot_variant
from knowledge.records import Event
from tests.benchmarks.runtime import percentiles
from tests.conftest import ROOT, wait_for


@dataclass
class Figures:
    """The samples of one fleet size, in seconds, and the load around them."""

    robots: int
    first_step: list[float] = field(default_factory=list)
    restarted: list[float] = field(default_factory=list)
    load: tuple[float, float] = (0.0, 0.0)  # 1-minute load average before, after


def depot_problem(names: Sequence[str], parcels: int) -> str:
    """The depot with these robots, each at a dock of its own, and parcels in the store."""
    docks = [f"dock{i + 1}" for i in range(len(names))]
    crates = [f"p{i + 1}" for i in range(parcels)]
    init = [f"(at {r} {d}) (hands_free {r}) (= (battery {r}) 100)" for r, d in zip(names, docks, strict=True)]  # fmt: skip
    init += [f"(road {d} store) (road store {d})" for d in docks]
    init += ["(road store lab) (road lab store) (road store office) (road office store)"]
    init += [f"(crate_at {c} store)" for c in crates]
    return (
        f"(define (problem depot-{len(names)}) (:domain depot)\n"
        f"  (:objects {' '.join(names)} - robot {' '.join(docks)} store lab office - place "
        f"{' '.join(crates)} - crate)\n"
        f"  (:init {' '.join(init)})\n  (:goal (and)))\n"
    )


@contextlib.contextmanager
def depot(folder: Path, count: int, parcels: int, scale: float) -> Iterator[
    tuple[FleetProcess, dict[str, RobotProcess]]
]:  # fmt: skip
    """N robots' executives, each in its own folder, and the fleet beside them."""
    names = [f"r{i + 1}" for i in range(count)]
    robots = {
        name: RobotProcess(
            robot_variant(EXAMPLE / "r1.yaml", folder / "descriptions" / name, {"robot": name}),
            folder / name,
            time_scale=scale,
        )
        for name in names
    }
    problem = folder / "problem.pddl"
    problem.write_text(depot_problem(names, parcels), encoding="utf-8")
    with contextlib.ExitStack() as stack:
        start_robots(robots.values(), stack)
        path = fleet_variant(
            EXAMPLE / "fleet.yaml", list(robots.values()), folder, problem=str(problem)
        )
        fleet = FleetProcess(path, folder / "fleet", time_scale=scale, join_wait=60.0)
        yield stack.enter_context(fleet), robots


def newest(fleet: FleetProcess) -> int:
    """The id of the fleet's newest event."""
    return fleet.events(limit=1)[-1].id


def first_start(fleet: FleetProcess, after: int, but: str = "", timeout: float = 120.0) -> Event:
    """The first START of a plan step logged after event ``after`` (on a robot other
    than ``but``)."""
    deadline = time.monotonic() + timeout
    while True:
        for e in fleet.events("START"):
            if e.id > after and (not but or f"({but}," not in e.subject):
                return e
        if time.monotonic() > deadline:
            raise TimeoutError(f"no step started within {timeout:g} s:\n{fleet.log_tail()}")
        time.sleep(0.05)


def rejoin(fleet: FleetProcess, robot: RobotProcess) -> None:
    """Start a killed robot's executive again and wait until the fleet has it back."""
    joined = len(fleet.events("ROBOT_JOINED"))
    robot.start()
    assert wait_for(lambda: len(fleet.events("ROBOT_JOINED")) > joined, 60), fleet.log_tail()


def measure(count: int, runs: int, scale: float, folder: Path) -> Figures:
    figures = Figures(count)
    before = os.getloadavg()[0]
    with depot(folder, count, runs, scale) as (fleet, robots):
        for run in range(1, runs + 1):
            after = newest(fleet)
            asked = time.time()
            goal = fleet.submit_goal(f"(crate_at p{run} lab)")
            started = first_start(fleet, after)
            figures.first_step.append(started.stamp - asked)
            worker = str(started.data["robot"])
            after = newest(fleet)
            killed = time.time()
            robots[worker].kill()
            if count == 1:
                robots[worker].start()
                again = first_start(fleet, after)
            else:
                again = first_start(fleet, after, but=worker)
            figures.restarted.append(again.stamp - killed)
            fleet.wait_for(goal, "achieved", timeout=180)
            if count > 1:
                rejoin(fleet, robots[worker])
    figures.load = (before, os.getloadavg()[0])
    return figures


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=5, help="goals (and kills) per fleet")
    parser.add_argument("--robots", default="1,2,5,10", help="fleet sizes (1: the baseline)")
    parser.add_argument("--scale", type=float, default=4.0, help="robot time speed-up")
    args = parser.parse_args()
    os.environ["PYTHONPATH"] = str(ROOT)
    sizes = [int(n) for n in args.robots.split(",")]
    results = []
    with tempfile.TemporaryDirectory() as tmp:
        for count in sizes:
            results.append(measure(count, args.runs, args.scale, Path(tmp) / f"fleet{count}"))
    print(f"fleet goal -> first step on its robot, and robot lost -> its work restarted "
          f"(robot time x{args.scale:g}; {os.cpu_count()} cores)")  # fmt: skip
    print(f"{'robots':<16} {'n':>3} {'goal p50 ms':>12} {'goal p95 ms':>12} "
          f"{'lost p50 ms':>12} {'lost p95 ms':>12} {'load':>11}")  # fmt: skip
    for f in results:
        g50, g95 = percentiles(f.first_step)
        l50, l95 = percentiles(f.restarted)
        name = f"{f.robots} (baseline)" if f.robots == 1 else str(f.robots)
        print(f"{name:<16} {len(f.first_step):>3} {g50 * 1000:>12.0f} {g95 * 1000:>12.0f} "
              f"{l50 * 1000:>12.0f} {l95 * 1000:>12.0f} {f.load[0]:>5.1f}-{f.load[1]:<5.1f}")  # fmt: skip


if __name__ == "__main__":
    main()
