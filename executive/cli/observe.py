"""``dura observe [--robot ROBOT.yaml] [--follow] [--json]``: what a running robot's observers see."""

from __future__ import annotations

import argparse
import contextlib
import json
import queue
import sys
import time
from typing import Any

from executive.bus.api.monitoring import OBSERVER_LATEST
from executive.bus.keys import OBSERVATIONS
from executive.bus.session import Bus
from executive.bus.wording import number
from executive.cli.client import add_client_options, connect
from executive.cli.output import add_json_flag, print_json, table

REDRAW = 1.0  # seconds between two tables with --follow


def register(sub: Any) -> None:
    p = sub.add_parser(
        "observe",
        help="show the current observations of a running robot",
        description="Ask the running executive's observer manager for the last observation "
        "of every observed resource and print them as a table (resource, type, state, "
        "measured value, age). With --follow, keep watching until Ctrl-C. Exit 1 if no "
        "executive runs.",
    )
    add_client_options(p)
    p.add_argument(
        "--follow",
        action="store_true",
        help="redraw the table as observations arrive (with --json: one JSON line each)",
    )
    add_json_flag(p)
    p.set_defaults(run=run)


def _key(payload: dict[str, Any]) -> tuple[str, str, str, str]:
    return (
        " ".join(payload.get("resource", [])),
        str(payload.get("type", "")),
        ",".join(payload.get("callerids", [])),
        str(payload.get("observer", "")),
    )


def _row(payload: dict[str, Any], now: float) -> list[str]:
    resource = " ".join(payload.get("resource", []))
    callerids = payload.get("callerids") or []
    if callerids:
        resource += f" [{', '.join(callerids)}]"
    values = payload.get("values") or {}
    value = ", ".join(_measured(k, v) for k, v in values.items()) or "-"
    age = max(0.0, now - float(payload.get("stamp", now)))
    state = f"{payload.get('observation_msg', '')} ({payload.get('observation')})"
    return [resource, str(payload.get("type", "")), state, value, f"{age:.1f} s"]


UNITS = {"frequency": "Hz", "silence": "s", "age": "s", "delay": "s", "cpu": "%"}


def _measured(quantity: str, value: float) -> str:
    """A measured value with its unit: ``frequency 10 Hz``, ``silence 0.06 s``."""
    if quantity == "memory":
        return f"memory {number(value / (1 << 20))} MiB"
    unit = UNITS.get(quantity, "")
    return f"{quantity} {number(value)}" + (f" {unit}" if unit else "")


def _table(observations: list[dict[str, Any]]) -> None:
    now = time.time()
    rows = [_row(p, now) for p in sorted(observations, key=_key)]
    table(["resource", "type", "state", "value", "age"], rows)


def _latest(bus: Bus) -> list[dict[str, Any]]:
    return OBSERVER_LATEST.call(bus).observations


def _follow(bus: Bus, as_json: bool) -> int:
    latest = {_key(o): o for o in _latest(bus)}
    if as_json:
        for payload in latest.values():
            sys.stdout.write(json.dumps(payload) + "\n")
    # the bus's thread only queues; this one prints (a blocked stdout never blocks the bus)
    arrived: queue.Queue[dict[str, Any]] = queue.Queue()
    bus.subscribe(OBSERVATIONS, lambda message: arrived.put(message.payload))
    redraw = 0.0
    try:
        while True:
            with contextlib.suppress(queue.Empty):
                payload = arrived.get(timeout=REDRAW)
                latest[_key(payload)] = payload
                if as_json:
                    sys.stdout.write(json.dumps(payload) + "\n")
            if as_json:
                sys.stdout.flush()
            elif time.monotonic() >= redraw:
                if sys.stdout.isatty():
                    sys.stdout.write("\x1b[H\x1b[2J")
                _table(list(latest.values()))
                sys.stdout.write("\n")
                sys.stdout.flush()
                redraw = time.monotonic() + REDRAW
    except KeyboardInterrupt:
        return 0


def run(args: argparse.Namespace) -> int:
    with connect(args) as bus:
        if args.follow:
            return _follow(bus, args.json)
        observations = _latest(bus)
    if args.json:
        now = time.time()
        print_json(
            {
                "observations": [
                    {**o, "age": max(0.0, now - float(o.get("stamp", now)))} for o in observations
                ]
            }
        )
    elif observations:
        _table(observations)
    else:
        print("no observations (no observer is active)")
    return 0
