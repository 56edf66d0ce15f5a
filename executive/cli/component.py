"""``dura component list|start|stop|restart|logs``: components of a running executive."""

from __future__ import annotations

import argparse
import time
from typing import Any

from executive.bus.keys import api
from executive.bus.payloads import ComponentState, Lifecycle
from executive.cli.client import add_client_options, connect
from executive.cli.output import add_json_flag, print_json, table
from executive.runtime.spawn import describe_exit
from knowledge.errors import DuraError


def register(sub: Any) -> None:
    p = sub.add_parser(
        "component", help="list, start, stop, restart, fault and reset components; show logs"
    )
    csub = p.add_subparsers(dest="component_command", metavar="COMPONENT_COMMAND")
    csub.required = True

    listing = csub.add_parser("list", help="every component with its state")
    add_client_options(listing)
    add_json_flag(listing)
    listing.set_defaults(run=run_list)

    for verb, text in (
        ("start", "start a component and wait until it is ready"),
        ("stop", "stop a component and wait until its process is gone"),
        ("restart", "restart a component; counts as a fault (at max_faults: permanently faulty)"),
        ("fault", "mark a component permanently faulty; its tasks move to alternatives"),
        ("reset", "clear a component's faults after maintenance"),
    ):
        cmd = csub.add_parser(verb, help=text)
        cmd.add_argument("name", metavar="NAME", help="the component")
        cmd.add_argument(
            "--timeout",
            type=float,
            default=60.0,
            metavar="SECONDS",
            help="how long to wait for the executive's answer (default 60)",
        )
        add_client_options(cmd)
        add_json_flag(cmd)
        cmd.set_defaults(run=run_lifecycle, verb=verb)

    logs = csub.add_parser("logs", help="the last lines of a component's log")
    logs.add_argument("name", metavar="NAME", help="the component")
    logs.add_argument(
        "-n", "--lines", type=int, default=50, metavar="N", help="how many lines (default 50)"
    )
    add_client_options(logs)
    add_json_flag(logs)
    logs.set_defaults(run=run_logs)


def _since(stamp: float) -> str:
    return time.strftime("%H:%M:%S", time.localtime(stamp)) if stamp else "-"


def run_list(args: argparse.Namespace) -> int:
    with connect(args) as bus:
        reply = bus.request(api("component/list"))
    if args.json:
        print_json(reply)
        return 0
    table(
        ["name", "kind", "state", "pid", "since", "reason"],
        [
            [c["component"], c["kind"], c["state"], c["pid"], _since(c["stamp"]), c["reason"]]
            for c in reply["components"]
        ],
    )
    return 0


def _summary(state: ComponentState) -> str:
    if state.state in (Lifecycle.READY, Lifecycle.STARTING, Lifecycle.PAUSED):
        return f"{state.component}: {state.state.value} (pid {state.pid})"
    if state.exit_code is None and state.signal is None:
        return f"{state.component}: {state.state.value} ({state.reason})"
    return (
        f"{state.component}: {state.state.value} ({describe_exit(state.exit_code, state.signal)})"
    )


def run_lifecycle(args: argparse.Namespace) -> int:
    if args.timeout <= 0:
        raise DuraError(f"--timeout must be positive, not {args.timeout:g}")
    with connect(args) as bus:
        reply = bus.request(
            api(f"component/{args.verb}"), {"name": args.name}, timeout=args.timeout
        )
    if args.verb == "reset":
        if args.json:
            print_json(reply)
        else:
            usable = ", ".join(reply["usable"]) or "nothing new"
            print(f"{args.name}: faults cleared; usable again: {usable}")
        return 0
    if "faults" in reply:  # restart and fault answer executive.bus.api.tasks.FaultReply:
        # {state, faults, permanent}; shown flat, as before, so --json output keeps its shape
        reply = {**reply["state"], "faults": reply["faults"], "permanent": reply["permanent"]}
    state = ComponentState.from_payload(reply)
    failed = state.state is Lifecycle.FAILED
    if args.json:
        print_json(reply)
        return 1 if failed else 0
    if failed:
        raise DuraError(f"'{state.component}' failed to start: {state.reason}")
    faults = ""
    if "faults" in reply:
        faults = f", {reply['faults']} faults" + (
            ", permanently faulty" if reply["permanent"] else ""
        )
    print(_summary(state) + faults)
    return 0


def run_logs(args: argparse.Namespace) -> int:
    if args.lines < 0:
        raise DuraError(f"--lines must be 0 or more, not {args.lines}")
    with connect(args) as bus:
        reply = bus.request(api("component/logs"), {"name": args.name, "lines": args.lines})
    if args.json:
        print_json(reply)
        return 0
    for line in reply["lines"]:
        print(line)
    return 0
