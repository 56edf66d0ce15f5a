"""``dura fleet run FLEET.yaml``: run a fleet's high level in the foreground: one plan for
several robots, each step run by the robot it names (each robot runs its own ``dura
run``)."""

from __future__ import annotations

import argparse
import contextlib
import os
import sys
from pathlib import Path
from typing import Any

from executive.cli.arguments import seconds
from executive.cli.client import remove_run_file, write_run_file
from executive.cli.output import add_json_flag, print_json, shown
from executive.cli.stopping import stop_on_signals, wait
from executive.fast_start import use_reader_environment
from knowledge.errors import ConfigError


def register(sub: Any) -> None:
    p = sub.add_parser(
        "fleet",
        help="run a fleet: one plan for several robots",
        description="Fleets: several robots, each with its own executive (dura run), "
        "sharing one temporal plan.",
    )
    commands = p.add_subparsers(dest="fleet_command", metavar="COMMAND", required=True)
    r = commands.add_parser(
        "run",
        help="run a fleet's high level in the foreground",
        description="Run a fleet's high level: goals (dura goal add), one temporal plan "
        "for all its robots, and each step run on the task executor of the robot it names, "
        "over that robot's bus, logged in as the fleet. A robot whose executive vanishes, "
        "or whose steps keep failing, is planned around until it is back. Ctrl-C or "
        "SIGTERM stops it (the robots' executives go on).",
    )
    r.add_argument("fleet", metavar="FLEET.yaml", type=Path, help="the fleet description")
    r.add_argument("--endpoint", help="listen here instead of the fleet's bus endpoint")
    r.add_argument("--db", type=Path, help="the knowledge base file (default: the fleet's)")
    r.add_argument(
        "--join-wait",
        type=seconds(zero=True),
        default=10.0,
        help="seconds to wait for the robots before the first plan (default 10)",
    )
    r.add_argument(
        "--lease",
        type=seconds(),
        default=3.0,
        metavar="SECONDS",
        help="silence after which a robot out of reach counts as lost (default 3)",
    )
    add_json_flag(r)
    r.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    use_reader_environment()
    from executive.fleet.fleet import Fleet
    from executive.fleet.validation import check_fleet

    check = check_fleet(args.fleet)
    errors = [f for f in check.findings if f.is_error]
    if errors or check.fleet is None:
        more = f" (and {len(errors) - 1} more: run 'dura validate {args.fleet}')"
        raise ConfigError(str(errors[0]) + (more if len(errors) > 1 else ""))
    fleet = check.fleet

    def say(line: str) -> None:
        if args.json:
            print_json({"fleet": fleet.name, "event": line})
        else:
            print(f"dura: fleet '{fleet.name}': {line}")
        sys.stdout.flush()

    stop = stop_on_signals()
    failure: list[str] = []

    def failed(reason: str) -> None:
        failure.append(reason)
        stop.set()

    running = Fleet(
        fleet,
        check.robots,
        check.actor_index,
        outside=check.outside,
        mappings=check.mappings,
        endpoint=args.endpoint,
        kb_path=args.db,
        join_wait=args.join_wait,
        lease=args.lease,
        on_failure=failed,
        say=say,
    )
    endpoint = running.endpoint
    running.on_open = lambda: write_run_file(
        fleet.name, endpoint, fleet.path, running.credentials_path
    )
    with contextlib.ExitStack() as stack:
        stack.callback(remove_run_file)
        stack.enter_context(running)
        if args.json:
            print_json({"fleet": fleet.name, "endpoint": endpoint, "pid": os.getpid(),
                        "robots": sorted(fleet.robots)})  # fmt: skip
        else:
            print(
                f"dura: fleet '{fleet.name}' of {', '.join(fleet.robots)} runs on {endpoint} "
                f"(pid {os.getpid()}, knowledge base {shown(running.kb_path)}); Ctrl-C stops it"
            )
        sys.stdout.flush()
        wait(stop)
    if failure:
        print(f"dura: {failure[0]}", file=sys.stderr)
        return 1
    if not args.json:
        print(f"dura: fleet '{fleet.name}' stopped")
    return 0
