"""``dura component list|start|stop|restart|logs``: components of a running executive."""

from __future__ import annotations

import argparse
import math
import time
from typing import Any

from executive.bus.api import components
from executive.bus.payloads import ComponentState
from executive.bus.states import Lifecycle
from executive.bus.wording import plural
from executive.cli import exits_at_once
from executive.cli.arguments import count, seconds
from executive.cli.client import add_client_options, ask
from executive.cli.output import add_json_flag, print_json, table
from knowledge.errors import DuraError


def register(sub: Any) -> None:
    p = sub.add_parser(
        "component",
        help="list, start, stop, restart, fault and reset components; inject faults; show logs",
    )
    exits_at_once(p)
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
            type=seconds(),
            default=60.0,
            metavar="SECONDS",
            help="how long to wait for the executive's answer (default 60)",
        )
        add_client_options(cmd)
        add_json_flag(cmd)
        cmd.set_defaults(run=run_lifecycle, verb=verb)

    inject = csub.add_parser(
        "inject",
        help="make a running component misbehave on purpose (fault injection)",
        description="Inject a fault into a running component: crash, hang, stop_publishing, "
        "wrong_rate, stale_timestamps, out_of_range, high_cpu, growing_memory, slip, or none "
        "(clear every fault). Options are numbers: after (seconds until it strikes), factor "
        "(wrong_rate), age (stale_timestamps), exit_code (crash), mb_per_s and limit_mb "
        "(growing_memory).",
    )
    inject.add_argument("name", metavar="NAME", help="the component")
    inject.add_argument("mode", metavar="MODE", help="the fault mode, e.g. crash or wrong_rate")
    inject.add_argument(
        "--option",
        "-o",
        action="append",
        default=[],
        metavar="K=V",
        help="an option of the mode, e.g. --option factor=0.5 (repeatable)",
    )
    add_client_options(inject)
    add_json_flag(inject)
    inject.set_defaults(run=run_inject)

    logs = csub.add_parser("logs", help="the last lines of a component's log")
    logs.add_argument("name", metavar="NAME", help="the component")
    logs.add_argument(
        "-n", "--lines", type=count, default=50, metavar="N", help="how many lines (default 50)"
    )
    add_client_options(logs)
    add_json_flag(logs)
    logs.set_defaults(run=run_logs)


def _since(stamp: float) -> str:
    return time.strftime("%H:%M:%S", time.localtime(stamp)) if stamp else "-"


def run_list(args: argparse.Namespace) -> int:
    reply = ask(args, components.COMPONENT_LIST)
    if args.json:
        print_json(reply.to_payload())
        return 0
    table(
        ["name", "kind", "host", "state", "pid", "since", "reason"],
        [
            [c.component, c.kind, c.host or "-", c.state.value, c.pid, _since(c.stamp), c.reason]
            for c in reply.components
        ],
    )  # fmt: skip
    for c in reply.components:
        if c.output:  # what a failed component wrote last: its exception
            print(f"\n{c.component} wrote last when it last failed:")
            print("\n".join(f"  {line}" for line in c.output))
    return 0


def _summary(state: ComponentState) -> str:
    from executive.runtime.spawn import describe_exit  # not for 'component list'

    if state.state in (Lifecycle.READY, Lifecycle.STARTING, Lifecycle.PAUSED):
        return f"{state.component}: {state.state.value} (pid {state.pid})"
    if state.exit_code is None and state.signal is None:
        return f"{state.component}: {state.state.value} ({state.reason})"
    return (
        f"{state.component}: {state.state.value} ({describe_exit(state.exit_code, state.signal)})"
    )


def run_lifecycle(args: argparse.Namespace) -> int:
    from executive.bus.api import tasks  # the task executor's verbs: not for 'component list'

    name, timeout = args.name, args.timeout
    if args.verb == "reset":
        reset = ask(args, tasks.COMPONENT_RESET, tasks.ComponentName(name), timeout=timeout)
        if args.json:
            print_json(reset.to_payload())
        else:
            print(
                f"{name}: faults cleared; usable again: {', '.join(reset.usable) or 'nothing new'}"
            )
        return 0
    if args.verb in ("restart", "fault"):
        faulting = tasks.COMPONENT_RESTART if args.verb == "restart" else tasks.COMPONENT_FAULT
        fault = ask(args, faulting, tasks.ComponentFault(name), timeout=timeout)
        state = fault.state
        faults = f", {plural(fault.faults, 'fault')}" + (
            ", permanently faulty" if fault.permanent else ""
        )
        payload = {**state.to_payload(), "faults": fault.faults, "permanent": fault.permanent}
    else:
        switch = components.COMPONENT_START if args.verb == "start" else components.COMPONENT_STOP
        state = ask(args, switch, components.ComponentName(name), timeout=timeout)
        faults, payload = "", state.to_payload()
    failed = state.state is Lifecycle.FAILED
    if args.json:
        print_json(payload)
        return 1 if failed else 0
    if failed:
        raise DuraError(f"'{state.component}' failed to start: {state.reason}")
    print(_summary(state) + faults)
    return 0


def _options(pairs: list[str]) -> dict[str, float]:
    """``K=V`` pairs as numbers (a whole number stays whole: ``exit_code=3``)."""
    options: dict[str, float] = {}
    for pair in pairs:
        key, sep, value = pair.partition("=")
        try:
            number = float(value) if sep and key else math.nan
        except ValueError:
            number = math.nan
        if not math.isfinite(number):
            raise DuraError(f"--option must be KEY=NUMBER, not '{pair}'")
        options[key] = int(number) if value.strip().lstrip("+-").isdigit() else number
    return options


def run_inject(args: argparse.Namespace) -> int:
    request = components.Injection(args.name, args.mode, _options(args.option))
    state = ask(args, components.COMPONENT_INJECT, request)
    if args.json:
        print_json({**state.to_payload(), "fault": {"mode": args.mode, **request.options}})
        return 0
    options = "".join(f", {k}={v:g}" for k, v in request.options.items())
    print(f"{state.component}: {args.mode} injected{options} (pid {state.pid})")
    return 0


def run_logs(args: argparse.Namespace) -> int:
    reply = ask(args, components.COMPONENT_LOGS, components.LogQuery(args.name, args.lines))
    if args.json:
        print_json(reply.to_payload())
        return 0
    for line in reply.lines:
        print(line)
    return 0
