"""A scripted publisher process: simulated robot hardware for the observer tests.

Usage: python -m tests.monitoring.publisher ROBOT ENDPOINT NAME PLAN_JSON

NAME is the caller id of every message. PLAN is ``{"streams": [stream, ...]}``; each
stream runs in a thread of its own: ``{"key": "topic/scan", "phases": [phase, ...]}``.
A phase publishes ``payload`` (default ``{}``) at ``rate`` Hz (0: silence) for
``duration`` seconds (absent: for ever), with ``"stamp": now - stamp_age`` (default 0)
added; with ``echo: {"key": ..., "delay": s}`` every message is followed ``delay``
seconds later by one on the echo key. After its last phase a stream falls silent,
but the process lives on (a hung publisher) until it is terminated.
"""

from __future__ import annotations

import json
import sys
import threading
import time
from typing import Any

from executive.bus.session import Bus


def run_phase(bus: Bus, key: str, phase: dict[str, Any], stop: threading.Event) -> None:
    rate = float(phase.get("rate", 0.0))
    duration = phase.get("duration")
    end = time.monotonic() + float(duration) if duration is not None else float("inf")
    if rate <= 0:
        stop.wait(max(0.0, end - time.monotonic()) if duration is not None else None)
        return
    payload = dict(phase.get("payload", {}))
    age = float(phase.get("stamp_age", 0.0))
    echo = phase.get("echo")
    period = 1.0 / rate
    due = time.monotonic()
    while not stop.is_set() and due < end:
        bus.publish(key, {**payload, "stamp": time.time() - age})
        if echo is not None:
            stop.wait(float(echo["delay"]))
            bus.publish(echo["key"], {"stamp": time.time()})
        due += period
        stop.wait(max(0.0, due - time.monotonic()))


def run_stream(bus: Bus, stream: dict[str, Any], stop: threading.Event) -> None:
    for phase in stream["phases"]:
        run_phase(bus, stream["key"], phase, stop)


def main() -> None:
    robot, endpoint, name, plan = sys.argv[1], sys.argv[2], sys.argv[3], json.loads(sys.argv[4])
    stop = threading.Event()
    with Bus(robot, name=name, endpoint=endpoint) as bus:
        threads = [
            threading.Thread(target=run_stream, args=(bus, s, stop), daemon=True)
            for s in plan["streams"]
        ]
        print("ready", flush=True)
        for thread in threads:
            thread.start()
        try:
            sys.stdin.read()  # until the test closes our stdin (or terminates us)
        finally:
            stop.set()
            for thread in threads:
                thread.join()


if __name__ == "__main__":
    main()
