"""Benchmark of the observer manager: message rate and CPU of frequency and timeout observers.

    python -m tests.benchmarks.observers [--duration S] [--topics 1,10,20,...]

The manager runs in this process, pinned to one core (CPU 0) with its bus (the router);
a publisher process pinned to another core (CPU 1) sends real zenoh messages on N
topics at 1 kHz each. Every topic has a frequency observer (mean over a 1000-period
window, 1 Hz loop) and a timeout observer (0.5 s). For each N the table shows the
aggregate rate the publisher achieved, the largest error of a measured frequency
against the publisher's own rate for that topic, this process's CPU use (all its
threads: zenoh's reception included) while the topics flow, the delay from sending a
message to its handler here (p50/p95: whether the observers keep up), and, once the
publisher stops, the time until the timeout observer of one topic reports it. It
stops after the first N whose error exceeds 1 %.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

from executive.bus.message import Message
from executive.bus.service import Context
from executive.bus.session import Bus
from knowledge.knowledge_base import KnowledgeBase
from knowledge.robot import read_robot
from monitoring.observer_manager import ObserverManager
from tests.conftest import free_endpoint
from tests.monitoring.harness import write_robot

RATE = 1000.0  # Hz per topic
TIMEOUT = 0.5  # s, of the timeout observers
KEEPING_UP = 50.0  # ms: the p95 send-to-handler delay of observers that keep up


def pin(cpu: int) -> None:
    """Pin this process (and the threads it starts from now on) to one core, if there are two."""
    if hasattr(os, "sched_setaffinity") and (os.cpu_count() or 1) > 1:
        os.sched_setaffinity(0, {cpu})


def publisher(robot: str, endpoint: str, topics: int, duration: float) -> None:
    """Publish ``topics`` topics at RATE for ``duration`` s once told; print the rates as JSON."""
    pin(1)
    data = b'{"stamp":0}'
    keys = [f"topic/t{i}" for i in range(topics)]
    counts = [0] * topics
    last = 0.0
    with Bus(robot, name="flood", endpoint=endpoint) as bus:
        print("ready", flush=True)
        sys.stdin.readline()
        period = 1.0 / RATE
        start = due = time.monotonic()
        end = start + duration
        while due < end:
            for i, key in enumerate(keys):
                bus.publish_raw(key, data)
                counts[i] += 1
            last = time.time()
            due += period
            pause = due - time.monotonic()
            if pause > 0:
                time.sleep(pause)
        elapsed = time.monotonic() - start
    print(json.dumps({"rates": [c / elapsed for c in counts], "stopped": last}), flush=True)


def observers(topic: str) -> list[dict[str, Any]]:
    ok = {"state": "ok", "number": 1, "frequency": {"type": "greater_than", "greater_than": 0}}
    return [
        {
            "type": "frequency",
            "main_loop_rate": 1.0,
            "topics": [
                {
                    "name": topic,
                    "filter": {"type": "mean", "window_size": int(RATE)},
                    "timeout": TIMEOUT,
                    "states": [ok],
                }
            ],
        },
        {"type": "timeout", "topics": [{"name": topic, "timeout": TIMEOUT}]},
    ]


def cpu_seconds() -> float:
    times = os.times()
    return times.user + times.system


def hang_detected(manager: ObserverManager, stopped: float) -> float:
    """Seconds from the publisher's last message to the first TIMEOUT report of t0."""
    deadline = time.monotonic() + 5.0
    while time.monotonic() < deadline:
        for o in manager.latest():
            if o["type"] == "timeout" and o["resource"] == ["t0"] and o["observation"] < 0:
                return float(o["stamp"]) - stopped
        time.sleep(0.005)
    return float("nan")


def run(topics: int, duration: float, folder: Path) -> dict[str, float]:
    endpoint = free_endpoint()
    robot, _ = read_robot(write_robot(folder, endpoint))
    assert robot is not None
    lags: list[float] = []

    def probe(message: Message) -> None:
        lags.append(message.received - (message.sent or message.received))

    with (
        Bus(robot.name, name="executive", endpoint=endpoint, listen=True) as bus,
        KnowledgeBase(folder / f"kb{topics}.db") as kb,
    ):
        manager = ObserverManager(Context(robot, bus, kb))
        manager.configure()
        manager.activate()
        try:
            for i in range(topics):
                for config in observers(f"t{i}"):
                    manager.add(config)
            flood = subprocess.Popen(
                [sys.executable, "-m", "tests.benchmarks.observers", "--publish",
                 robot.name, endpoint, str(topics), str(duration)],
                stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True,
            )  # fmt: skip
            assert flood.stdin is not None and flood.stdout is not None
            assert flood.stdout.readline().strip() == "ready"
            flood.stdin.write("go\n")
            flood.stdin.flush()
            time.sleep(1.5)  # the windows fill
            probing = bus.subscribe("topic/t0", probe, decoded=False)
            cpu0, wall0 = cpu_seconds(), time.monotonic()
            time.sleep(duration - 2.5)
            cpu = (cpu_seconds() - cpu0) / (time.monotonic() - wall0) * 100
            probing.undeclare()
            measured = {
                o["resource"][0]: o["values"]["frequency"]
                for o in manager.latest()
                if o["type"] == "frequency"
            }
            report = json.loads(flood.stdout.readline())
            flood.wait(30)
            hang = hang_detected(manager, report["stopped"])
        finally:
            manager.shutdown()
    rates = report["rates"]
    errors = [abs(measured.get(f"t{i}", 0.0) - r) / r for i, r in enumerate(rates)]
    return {
        "rate": sum(rates),
        "error": max(errors) * 100,
        "cpu": cpu,
        "lag": statistics.median(lags) * 1000,
        "lag95": statistics.quantiles(lags, n=20)[18] * 1000,
        "hang": hang,
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=(__doc__ or "").split("\n")[0])
    parser.add_argument("--duration", type=float, default=6.0, help="seconds per step (6)")
    parser.add_argument(
        "--topics",
        default="1,5,10,20,30,40,50,60,80,100",
        help="topic counts to try (1,5,10,20,...,100)",
    )
    parser.add_argument("--publish", nargs=4, help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.publish:
        robot, endpoint, topics, duration = args.publish
        publisher(robot, endpoint, int(topics), float(duration))
        return
    pin(0)
    print(f"observers on one core (CPU 0), publisher on CPU 1; topics at {RATE:g} Hz each")
    print(
        f"{'topics':>6}  {'msg/s':>8}  {'max error %':>11}  {'CPU %':>6}  {'CPU % per kHz':>13}  "
        f"{'lag p50/p95 ms':>14}  {'hang seen after s':>17}"
    )
    accurate = kept_up = 0.0
    with tempfile.TemporaryDirectory() as folder:
        for topics in (int(n) for n in args.topics.split(",")):
            row = run(topics, args.duration, Path(folder))
            print(
                f"{topics:>6}  {row['rate']:>8.0f}  {row['error']:>11.3f}  {row['cpu']:>6.1f}  "
                f"{row['cpu'] / topics:>13.2f}  {row['lag']:>6.1f} /{row['lag95']:>6.1f}  "
                f"{row['hang']:>17.3f}",
                flush=True,
            )
            if row["error"] > 1.0:
                break
            accurate = max(accurate, row["rate"])
            if row["lag95"] <= KEEPING_UP:
                kept_up = max(kept_up, row["rate"])
    print(f"max aggregate rate with every frequency within 1 %: {accurate:.0f} msg/s")
    print(
        "max aggregate rate with every frequency within 1 % and the observers keeping up "
        f"(p95 lag <= {KEEPING_UP:g} ms): {kept_up:.0f} msg/s"
    )
    print(
        f"(timeout {TIMEOUT:g} s, loop {TIMEOUT / 4:g} s: a hang is due within {TIMEOUT * 1.25:g} s)"
    )


if __name__ == "__main__":
    main()
