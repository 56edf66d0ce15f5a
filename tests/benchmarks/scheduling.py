"""Benchmark of the scheduler: how long one schedule takes for many concurrent requests.

    python -m tests.benchmarks.scheduling [--runs N] [--time-limit S]

Prints, per number of concurrent requests on generated robots (a quarter of them
running, some with deadlines, some starting together, one faulty functionality):
p50/p95 milliseconds of a whole ``Scheduler.schedule`` call (grounding, solving,
explaining cancellations), how many results were proven optimal, and the average
numbers of scheduled and cancelled requests. Target: <= 50 ms for 20 requests.
"""

from __future__ import annotations

import argparse
import statistics

from executive.schedule import ScheduleStatus
from executive.scheduler import Scheduler
from tests.executive.scheduling_cases import generate

SIZES = (5, 20, 50, 200)


def percentiles(samples: list[float]) -> tuple[float, float]:
    cuts = statistics.quantiles(samples, n=20, method="inclusive")
    return statistics.median(samples), cuts[18]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=20, help="generated problems per size")
    parser.add_argument("--time-limit", type=float, default=1.0, help="solver time limit (s)")
    parser.add_argument("--sizes", type=int, nargs="*", default=list(SIZES))
    args = parser.parse_args()
    print(
        f"{'requests':>8} {'p50 ms':>8} {'p95 ms':>8} {'optimal':>8} {'scheduled':>9} {'cancelled':>9}"
    )
    for size in args.sizes:
        times: list[float] = []
        optimal = scheduled = cancelled = 0
        for seed in range(args.runs):
            problem = generate(size, seed)
            scheduler = Scheduler(problem.functionalities, time_limit=args.time_limit)
            result = scheduler.schedule(problem.requests, faulty=problem.faulty)
            times.append(result.solve_time * 1000)
            optimal += result.status is ScheduleStatus.OPTIMAL
            scheduled += len(result.assignments)
            cancelled += len(result.cancelled)
        p50, p95 = percentiles(times)
        print(
            f"{size:>8} {p50:>8.1f} {p95:>8.1f} {optimal:>4}/{args.runs:<3} "
            f"{scheduled / args.runs:>9.1f} {cancelled / args.runs:>9.1f}"
        )


if __name__ == "__main__":
    main()
