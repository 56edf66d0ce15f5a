"""Benchmark of the scheduler: how long one schedule takes for many concurrent requests.

    python -m tests.benchmarks.scheduling [--runs N] [--time-limit S] [--sizes 5 20 ...]

Prints, per number of concurrent requests on generated robots (a quarter of them
running, some with deadlines, some starting together, one faulty functionality; see
``tests/executive/scheduling_cases.generate``): wall-clock p50/p95 and CPU p50
milliseconds of a whole ``Scheduler.schedule`` call (grounding, solving, explaining
cancellations), how many results were proven optimal within the time limit, and the
average numbers of scheduled and cancelled requests. Target: <= 50 ms for 20.

Then the fault-to-reconfigured latency of thesis scenario 2 (SIGKILL of lidar at its
third fault until cam_to_lidar publishes scan_filtered), which needs the runtime.
"""

from __future__ import annotations

import argparse
import os
import signal
import statistics
import tempfile
import time
from collections.abc import Callable
from pathlib import Path

from executive.bus.keys import topic
from executive.tasks.schedule import ScheduleStatus
from executive.tasks.scheduler import Scheduler
from executive.testing.harness import RobotProcess, robot_variant
from tests.conftest import USECASE, wait_for
from tests.executive.tasks.scheduling_cases import generate

SIZES = (5, 20, 50, 200)


def percentiles(samples: list[float]) -> tuple[float, float]:
    cuts = statistics.quantiles(samples, n=20, method="inclusive")
    return statistics.median(samples), cuts[18]


def schedule_times(sizes: list[int], runs: int, time_limit: float) -> None:
    print(
        f"{'requests':>8} {'p50 ms':>8} {'p95 ms':>8} {'cpu p50':>8} {'optimal':>8}"
        f" {'scheduled':>9} {'cancelled':>9}"
    )
    for size in sizes:
        wall: list[float] = []
        cpu: list[float] = []
        optimal = scheduled = cancelled = 0
        for seed in range(runs):
            problem = generate(size, seed)
            scheduler = Scheduler(problem.functionalities, time_limit=time_limit)
            began = time.process_time()
            result = scheduler.schedule(problem.requests, faulty=problem.faulty)
            cpu.append((time.process_time() - began) * 1000)
            wall.append(result.solve_time * 1000)
            optimal += result.status is ScheduleStatus.OPTIMAL
            scheduled += len(result.assignments)
            cancelled += len(result.cancelled)
        p50, p95 = percentiles(wall)
        print(
            f"{size:>8} {p50:>8.1f} {p95:>8.1f} {statistics.median(cpu):>8.1f}"
            f" {optimal:>4}/{runs:<3} {scheduled / runs:>9.1f} {cancelled / runs:>9.1f}"
        )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=20, help="generated problems per size")
    parser.add_argument("--time-limit", type=float, default=1.0, help="solver time limit (s)")
    parser.add_argument("--sizes", type=int, nargs="*", default=list(SIZES))
    parser.add_argument(
        "--failovers", type=int, default=10, help="runs of the scenario 2 failover (0: none)"
    )
    args = parser.parse_args()
    schedule_times(args.sizes, args.runs, args.time_limit)
    if args.failovers:
        failover(args.failovers)


def _wait(check: Callable[[], bool], timeout: float = 30.0) -> None:
    if not wait_for(check, timeout):
        raise TimeoutError("the robot did not get there in time")


def _failover_once(folder: Path) -> float:
    """Scenario 2 with a real executive: move_to runs on lidar + lidar_filter; lidar is
    restarted twice (faults 1 and 2), then SIGKILLed (fault 3, permanent). Returns the
    seconds from the kill until cam_to_lidar's first scan_filtered."""
    description = robot_variant(
        USECASE, folder / "robot", {"behaviors": {"move_to": {"params": {"duration": 60.0}}}}
    )
    with RobotProcess(description, folder / "run") as robot:
        task = robot.request("task/start", {"task": "move_to", "goal": {"target": "lab"}})["id"]

        def starts() -> int:
            return sum(
                e["subject"].startswith(f"task {task} ") for e in robot.events("TASK_STARTED")
            )

        for fault in (1, 2):
            _wait(lambda: starts() >= fault)  # noqa: B023
            robot.request("component/restart", {"name": "lidar", "reason": "benchmark"})
        _wait(lambda: starts() >= 3)
        arrived: list[float] = []
        robot.bus.subscribe(
            topic("scan_filtered"),
            lambda m: arrived.append(time.time()) if m.caller_id == "cam_to_lidar" else None,
        )
        listed = robot.request("component/list")["components"]
        pid = next(c["pid"] for c in listed if c["component"] == "lidar")
        killed = time.time()
        os.kill(pid, signal.SIGKILL)
        _wait(lambda: bool(arrived))
        return arrived[0] - killed


def failover(runs: int) -> None:
    samples = []
    with tempfile.TemporaryDirectory(prefix="dura-failover-") as tmp:
        for run in range(runs):
            samples.append(_failover_once(Path(tmp) / str(run)) * 1000)
            print(f"  failover run {run + 1}/{runs}: {samples[-1]:.0f} ms", flush=True)
    p50, p95 = percentiles(samples) if len(samples) > 1 else (samples[0], samples[0])
    print(
        "\nfault-to-reconfigured, scenario 2 (SIGKILL of lidar at its third fault until "
        "cam_to_lidar publishes scan_filtered)"
    )
    print(f"{'runs':>8} {'p50 ms':>8} {'p95 ms':>8} {'min ms':>8} {'max ms':>8}")
    print(f"{runs:>8} {p50:>8.0f} {p95:>8.0f} {min(samples):>8.0f} {max(samples):>8.0f}")


if __name__ == "__main__":
    main()
