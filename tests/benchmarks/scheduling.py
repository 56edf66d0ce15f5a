"""Benchmark of the scheduler: how long one schedule takes for many concurrent requests.

    python -m tests.benchmarks.scheduling [--runs N] [--time-limit S] [--sizes 5 20 ...]

Prints, per number of concurrent requests on generated robots (a quarter of them
running, some with deadlines, some starting together, one faulty functionality; see
``tests/executive/scheduling_cases.generate``): wall-clock p50/p95 and CPU p50
milliseconds of a whole ``Scheduler.schedule`` call (grounding, solving, explaining
cancellations), how many results were proven optimal within the time limit, and the
average numbers of scheduled and cancelled requests. Target: <= 50 ms for 20.

Then the failover latency of thesis scenario 2 (SIGKILL of lidar at its last fault until
cam_to_lidar's first scan_filtered reaches a subscriber) with a real executive: the
sequential baseline (``dura run --starts sequential``: stop, then start one after
another), the parallel make-before-break change, and a warm spare (``standby: true`` on
cam_to_lidar), each quiet and with a second process loading a core, as ratios to the
baseline of the same load. Target: p95 <= 150 ms quiet, <= 300 ms loaded.
"""

from __future__ import annotations

import argparse
import os
import signal
import statistics
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

from executive.bus.keys import topic
from executive.tasks.schedule import ScheduleStatus
from executive.tasks.scheduler import Scheduler
from executive.testing.harness import RobotProcess, robot_variant
from tests.conftest import USECASE, wait_for
from tests.executive.tasks.scheduling_cases import generate

SIZES = (5, 20, 50, 200)


def percentiles(samples: list[float]) -> tuple[float, float]:
    """The median and the 95th percentile (of one sample: that sample)."""
    if len(samples) < 2:
        return samples[0], samples[0]
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
        "--failovers", type=int, default=10, help="failovers per variant and load (0: none)"
    )
    args = parser.parse_args()
    schedule_times(args.sizes, args.runs, args.time_limit)
    if args.failovers:
        failover(args.failovers)


def _wait(check: Callable[[], bool], timeout: float = 30.0) -> None:
    if not wait_for(check, timeout):
        raise TimeoutError("the robot did not get there in time")


# How a configuration changes, and what it starts from: the baseline first.
VARIANTS: dict[str, tuple[list[str], dict[str, Any]]] = {
    "sequential (baseline)": (["--starts", "sequential"], {}),
    "parallel, make before break": ([], {}),
    "parallel + warm spare": ([], {"cam_to_lidar": {"standby": True}}),
}


def _failover_runs(
    folder: Path, options: list[str], spares: dict[str, Any], runs: int
) -> list[float]:
    """Scenario 2 with a real executive, ``runs`` times: move_to runs on lidar +
    lidar_filter; lidar (max_faults 1 here: its SIGKILL is its last fault) is SIGKILLed;
    the seconds from the kill until cam_to_lidar's first scan_filtered reaches a
    subscriber. Between runs lidar is reset and move_to asked for again."""
    changes = {
        "behaviors": {"move_to": {"params": {"duration": 600.0}}},
        "functionalities": {"lidar": {"max_faults": 1}, **spares},
    }
    description = robot_variant(USECASE, folder / "robot", changes)
    samples: list[float] = []
    with RobotProcess(description, folder / "run", run_args=options) as robot:
        arrived: list[float] = []
        robot.bus.subscribe(
            topic("scan_filtered"),
            lambda m: arrived.append(time.time()) if m.caller_id == "cam_to_lidar" else None,
        )

        def listed(name: str) -> dict[str, Any]:
            components = robot.request("component/list")["components"]
            return dict(next(c for c in components if c["component"] == name))

        for _ in range(runs):
            task = robot.request("task/start", {"task": "move_to", "goal": {"target": "lab"}})
            _wait(lambda: robot.request("task/list")["tasks"][-1]["state"] == "running")
            _wait(lambda: listed("cam_to_lidar")["state"] != "ready")  # a spare is paused
            time.sleep(0.5)  # let the idle spare settle
            arrived.clear()
            killed = time.time()
            os.kill(listed("lidar")["pid"], signal.SIGKILL)
            _wait(lambda: bool(arrived))
            samples.append(arrived[0] - killed)
            robot.request("task/stop", {"id": task["id"]})
            robot.request("component/reset", {"name": "lidar"})
            _wait(lambda: listed("cam_to_lidar")["state"] != "ready")
    return samples


def failover(runs: int) -> None:
    """Failover latency of each variant, quiet and with a second process loading a core,
    each against the sequential baseline measured in the same run."""
    rows: list[tuple[str, str, list[float]]] = []
    with tempfile.TemporaryDirectory(prefix="dura-failover-") as tmp:
        for load in ("quiet", "loaded"):
            loader = _load() if load == "loaded" else None
            try:
                for i, (name, (options, spares)) in enumerate(VARIANTS.items()):
                    folder = Path(tmp) / f"{load}-{i}"
                    samples = [s * 1000 for s in _failover_runs(folder, options, spares, runs)]
                    rows.append((load, name, samples))
                    print(f"  {load:<6} {name:<28} {' '.join(f'{x:.0f}' for x in samples)} ms",
                          flush=True)  # fmt: skip
            finally:
                if loader is not None:
                    loader.kill()
                    loader.wait()
    print(
        "\nfailover, scenario 2 (SIGKILL of lidar at its last fault until cam_to_lidar's first "
        "scan_filtered reaches a subscriber), against the sequential baseline of the same load"
    )
    print(f"{'load':<7} {'variant':<28} {'runs':>4} {'p50 ms':>7} {'p95 ms':>7} {'max ms':>7} "
          f"{'p95 / baseline':>15}")  # fmt: skip

    def cut(samples: list[float]) -> tuple[float, float]:
        return percentiles(samples) if len(samples) > 1 else (samples[0], samples[0])

    baseline = {load: cut(samples)[1] for load, name, samples in rows if "baseline" in name}
    for load, name, samples in rows:
        p50, p95 = cut(samples)
        print(f"{load:<7} {name:<28} {len(samples):>4} {p50:>7.0f} {p95:>7.0f} "
              f"{max(samples):>7.0f} {p95 / baseline[load]:>15.2f}")  # fmt: skip


def _load() -> subprocess.Popen[bytes]:
    """A second process that keeps one core busy."""
    return subprocess.Popen([sys.executable, "-c", "while True: pass"])


if __name__ == "__main__":
    main()
