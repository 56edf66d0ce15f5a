"""Dashboard: how soon a lidar fault shows on the page (the issue: within 2 s of the
executive's diagnosis).

    python -m tests.benchmarks.dashboard [--faults N]

N times, a real executive of the use case and its dashboard, shown in Debian's headless
Chromium (one browser for all): the robot drives on lidar, lidar stops publishing (an
injected fault), the executive diagnoses it, and the page draws lidar's node faulty. For each stage the table gives the median, p95 and the
largest time, on the machine's wall clock (the page's and the executive's are the same
clock): from the injection to the diagnosis (its stamp), from the diagnosis to a bus
subscriber in this process (the baseline: what the bus alone takes to deliver it), and
from the diagnosis to the page.
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
import tempfile
import threading
import time
from pathlib import Path

from executive.bus.keys import DIAGNOSES
from executive.bus.message import Message
from executive.dashboard.server import Dashboard
from executive.testing.harness import RobotProcess
from tests.conftest import USECASE
from tests.executive.dashboard.browser import Browser, chromium
from tests.executive.dashboard.driving import LIDAR_FAULTY, drive, watch_lidar

DIAGNOSED_WITHIN = 30.0  # s
STAGES = (
    "fault injected -> diagnosis (its stamp)",
    "diagnosis -> a bus subscriber here (baseline)",
    "diagnosis -> lidar faulty on the page",
)


def rounds(faults: int, folder: Path) -> list[tuple[float, float, float]]:
    """Each fault's three stages, in seconds."""
    out = []
    with Browser() as browser:
        for n in range(faults):
            out.append(one_fault(browser, folder / str(n)))
            print(f"\r{n + 1}/{faults} faults", end="", file=sys.stderr)
    print(file=sys.stderr)
    return out


def one_fault(browser: Browser, folder: Path) -> tuple[float, float, float]:
    """A fault of lidar on a robot of its own, as the page shows it."""
    folder.mkdir()
    with (
        RobotProcess(USECASE, folder) as robot,
        Dashboard.connect(robot.robot, robot.endpoint, port=0, folders=[robot.folder]) as page,
    ):
        browser.open(page.url)
        heard: list[tuple[float, float]] = []  # (stamp, heard) of the diagnosis of lidar
        got = threading.Event()

        def on_diagnosis(message: Message) -> None:
            if ["lidar"] in message.payload.get("diagnoses", []) and not got.is_set():
                heard.append((float(message.payload["stamp"]), time.time()))
                got.set()

        robot.bus.subscribe(DIAGNOSES, on_diagnosis)
        drive(robot)
        watch_lidar(browser)
        injected = time.time()
        robot.inject_fault("lidar", "stop_publishing")
        if not got.wait(DIAGNOSED_WITHIN):
            sys.exit(f"lidar not diagnosed within {DIAGNOSED_WITHIN:g} s")
        shown = browser.wait_for(LIDAR_FAULTY, timeout=30.0) / 1000.0
        stamp, at = heard[0]
        return stamp - injected, at - stamp, shown - stamp


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--faults", type=int, default=10, help="lidar faults")
    args = parser.parse_args()
    if chromium() is None:
        sys.exit("no Chromium here: 'apt-get install chromium'")
    began = time.monotonic()
    with tempfile.TemporaryDirectory(prefix="dura-dashboard-") as name:
        measured = rounds(args.faults, Path(name))
    print(f"{args.faults} lidar faults, {time.monotonic() - began:.0f} s, "
          f"load average {os.getloadavg()[0]:.1f}")  # fmt: skip
    print(f"{'stage':<48} {'median ms':>10} {'p95 ms':>8} {'max ms':>8}")
    for i, stage in enumerate(STAGES):
        times = sorted(1000.0 * r[i] for r in measured)
        p95 = times[min(len(times) - 1, round(0.95 * (len(times) - 1)))]
        print(f"{stage:<48} {statistics.median(times):>10.0f} {p95:>8.0f} {times[-1]:>8.0f}")


if __name__ == "__main__":
    main()
