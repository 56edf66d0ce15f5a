"""Benchmark of the high level's second step, with real executives and components.

    python -m tests.benchmarks.high_level [--runs N] [--skip-scale] [--skip-ahead]

1. **Time scale.** The transport robot's delivery (``(crate_at parcel lab)``, seven
   steps, the e2e test's scenario) in real time and with ``DURA_TIME_SCALE=10``, in the
   same run: wall seconds from the goal's submission to its achievement and for the
   whole run (executive start and stop included), and the speed-up. Twice: with the
   example's components as they are (their steps are shorter than the planner's
   estimates), and with components whose steps take what the domain says ("as
   planned": a 42 s plan).
2. **Watching the plan ahead.** The same delivery, real time: a road the plan takes
   later, ``(road store hall0)``, is blocked while the robot drives to the store.
   Without the block, the robot gets to that road (the step is dispatched) some
   seconds after the plan started; with it, the executor replans right after the
   block. The table shows both, and how much earlier the replan comes than the robot
   would have found the road blocked (the executor without watching ahead replans
   only then: the step cannot start).
"""

from __future__ import annotations

import argparse
import statistics
import tempfile
import time
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from executive.testing.harness import RobotProcess, robot_variant
from knowledge.records import Event
from tests.conftest import ROOT

TRANSPORT = ROOT / "examples" / "transport" / "robot.yaml"
GOAL = "(crate_at parcel lab)"
AS_PLANNED: dict[str, Any] = {
    "behaviors": {"drive_to": {"params": {"duration": 5.0}}, "ride_lift": {"params": {"drive": 1.0}}},
    "functionalities": {"lift_link": {"params": {"travel": 4.0}}, "gripper": {"params": {"actuation": 2.5}}},
}  # fmt: skip
BLOCKED = "(road store hall0)"
BLOCKED_STEP = "drive(store, hall0)"


def robot(folder: Path, changes: Mapping[str, Any], scale: float | None) -> RobotProcess:
    description = (
        robot_variant(TRANSPORT, folder / "description", changes) if changes else TRANSPORT
    )
    return RobotProcess(description, folder, time_scale=scale)


def stamp(events: list[Event], kind: str, subject: str = "") -> float:
    return next(e.stamp for e in events if e.kind == kind and subject in e.subject)


def delivery(changes: Mapping[str, Any], scale: float | None) -> tuple[float, float]:
    """Seconds from the goal to its achievement, and for the whole run."""
    with tempfile.TemporaryDirectory() as tmp:
        began = time.monotonic()
        r = robot(Path(tmp), changes, scale)
        r.start()
        try:
            submitted = time.monotonic()
            r.wait_for(r.submit_goal(GOAL), "achieved", timeout=600)
            achieved = time.monotonic()
        finally:
            r.stop()
        return achieved - submitted, time.monotonic() - began


def time_scale(runs: int) -> None:
    print("1. time scale: the transport delivery, real time and DURA_TIME_SCALE=10")
    print(f"{'components':<14} {'scale':>5} {'goal s':>8} {'run s':>8} {'speed-up':>9}")
    for name, changes in (("as they are", {}), ("as planned", AS_PLANNED)):
        results: dict[float, tuple[float, float]] = {}
        for scale in (1.0, 10.0):
            samples = [delivery(changes, scale) for _ in range(runs)]
            results[scale] = (
                statistics.median(s[0] for s in samples),
                statistics.median(s[1] for s in samples),
            )
        for scale, (goal, run) in results.items():
            ratio = results[1.0][0] / goal
            print(f"{name:<14} {scale:>5g} {goal:>8.2f} {run:>8.2f} {ratio:>8.1f}x")
    print()


def ahead(runs: int) -> None:
    print("2. watching the plan ahead: the road store -> hall0 blocked during the first drive")
    print(
        f"{'run':>3} {'robot at the road s':>20} {'block s':>8} {'replan s':>9} {'earlier s':>10}"
    )
    for n in range(runs):
        with tempfile.TemporaryDirectory() as tmp:
            r = robot(Path(tmp) / "free", {}, None)
            r.start()
            try:
                r.wait_for(r.submit_goal(GOAL), "achieved", timeout=600)
                events = r.events()
            finally:
                r.stop()
            began = stamp(events, "PLAN_START")
            there = stamp(events, "DISPATCH", BLOCKED_STEP) - began
            r = robot(Path(tmp) / "blocked", {}, None)
            r.start()
            try:
                goal = r.submit_goal(GOAL)
                r.wait_for_event("START", "drive(dock, store)", timeout=60)
                r.unset_fact(BLOCKED)
                r.wait_for(goal, "achieved", timeout=600)
                events = r.events()
            finally:
                r.stop()
            began = stamp(events, "PLAN_START")
            blocked = stamp(events, "STATE_UNSET", BLOCKED) - began
            replan = stamp(events, "REPLAN") - began
            print(
                f"{n + 1:>3} {there:>20.2f} {blocked:>8.2f} {replan:>9.2f} {there - replan:>10.2f}"
            )
    print("(seconds after the plan started; 'earlier': when the robot would have found the")
    print(" road blocked, minus when the executor watching ahead replanned)")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--runs", type=int, default=1, help="runs per row (median)")
    parser.add_argument("--skip-scale", action="store_true", help="leave out the time scale")
    parser.add_argument("--skip-ahead", action="store_true", help="leave out watching ahead")
    args = parser.parse_args()
    if not args.skip_scale:
        time_scale(args.runs)
    if not args.skip_ahead:
        ahead(args.runs)


if __name__ == "__main__":
    main()
