"""Benchmark of the low-level runtime: how fast components start, stop and are reported.

    python -m tests.benchmarks.runtime [--runs N]

Prints p50/p95 (milliseconds) of:
- start-to-ready: ``Launcher.start`` of the lidar until it returns READY;
- stop-to-stopped: ``Launcher.stop`` of a ready lidar until its process is reaped;
- exit-to-reported: SIGKILL of the lidar until a bus client receives EXITED;
- executive-kill-to-gone: SIGKILL of ``dura run`` with three components until all are gone.
"""

from __future__ import annotations

import argparse
import os
import signal
import statistics
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

import psutil

from executive.bus.keys import component
from executive.bus.message import Message
from executive.bus.session import Bus
from tests.conftest import ROOT, USECASE, free_endpoint, run_dura, wait_for
from tests.executive.runtime.rig import rig, robot, usecase


def percentiles(samples: list[float]) -> tuple[float, float]:
    cuts = statistics.quantiles(samples, n=20, method="inclusive")
    return statistics.median(samples), cuts[18]


def launcher_latencies(runs: int, folder: Path) -> dict[str, list[float]]:
    out: dict[str, list[float]] = {
        "start-to-ready": [],
        "stop-to-stopped": [],
        "exit-to-reported": [],
    }
    endpoint = free_endpoint()
    with (
        rig(robot(usecase("lidar")), endpoint, folder) as r,
        Bus(r.robot.name, name="observer", endpoint=endpoint) as observer,
    ):
        exited = threading.Event()
        received: list[float] = []

        def on_state(message: Message) -> None:
            if message.payload["state"] == "exited":
                received.append(message.received)
                exited.set()

        observer.subscribe(component("lidar", "state"), on_state)
        for i in range(runs):
            began = time.perf_counter()
            state = r.launcher.start("lidar")
            out["start-to-ready"].append(time.perf_counter() - began)
            if i % 2 == 0:
                began = time.perf_counter()
                r.launcher.stop("lidar")
                out["stop-to-stopped"].append(time.perf_counter() - began)
                continue
            exited.clear()
            assert state.pid is not None
            killed = time.time()
            os.kill(state.pid, signal.SIGKILL)
            assert exited.wait(10)
            out["exit-to-reported"].append(received[-1] - killed)
            wait_for(lambda: not r.launcher.state("lidar").state.is_alive)
    return out


def executive_kill(runs: int, folder: Path) -> list[float]:
    samples = []
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    for _ in range(runs):
        endpoint = free_endpoint()
        process = subprocess.Popen(
            [sys.executable, "-m", "executive.cli", "run", str(USECASE), "--endpoint", endpoint],
            cwd=folder,
            env=env,
            stdout=subprocess.PIPE,
            stderr=subprocess.DEVNULL,
            text=True,
        )
        try:
            assert process.stdout is not None
            process.stdout.readline()
            for name in ("lidar", "lidar_filter", "cam"):
                run_dura("component", "start", name, cwd=folder)
            children = psutil.Process(process.pid).children(recursive=True)
            killed = time.perf_counter()
            process.kill()
            process.wait()
            while not all(_gone(c) for c in children):
                time.sleep(0.001)
            samples.append(time.perf_counter() - killed)
        finally:
            process.kill()
            process.wait()
            if process.stdout is not None:
                process.stdout.close()
    return samples


def _gone(process: psutil.Process) -> bool:
    try:
        return process.status() == psutil.STATUS_ZOMBIE
    except psutil.NoSuchProcess:
        return True


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=40, help="samples per launcher latency")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        os.environ["PYTHONPATH"] = str(ROOT)
        results = launcher_latencies(args.runs, Path(tmp))
        results["executive-kill-to-gone"] = executive_kill(max(3, args.runs // 8), Path(tmp))
    print(f"{'latency':<24} {'n':>4} {'p50 ms':>8} {'p95 ms':>8}")
    for name, samples in results.items():
        p50, p95 = percentiles(samples)
        print(f"{name:<24} {len(samples):>4} {p50 * 1000:>8.1f} {p95 * 1000:>8.1f}")


if __name__ == "__main__":
    main()
