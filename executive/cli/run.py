"""``dura run ROBOT.yaml``: run the executive in the foreground until Ctrl-C or SIGTERM."""

from __future__ import annotations

import argparse
import contextlib
import logging
import os
import sys
import threading
from collections.abc import Iterator
from pathlib import Path
from typing import Any

from executive.bus.keys import DIAGNOSES, EVENTS
from executive.cli.arguments import add_launcher_options, megabytes, seconds
from executive.cli.client import remove_run_file, write_run_file
from executive.cli.dashboard import add_dashboard_address, port
from executive.cli.demo_timeline import Timeline, WarningLines
from executive.cli.output import add_json_flag, print_json, shown
from executive.cli.progress import LiveLine
from executive.cli.stopping import stop_on_signals, wait
from executive.executive import SEPARABLE, Executive, ServiceProcess
from executive.runtime.launcher import local_endpoint
from executive.runtime.native_heap import HeapTrimmer, limit_arenas
from knowledge.description import RobotDescription
from knowledge.robot import load_robot


def register(sub: Any) -> None:
    p = sub.add_parser(
        "run",
        help="run the executive for a robot in the foreground",
        description="Run the executive for a robot: its bus (listening), knowledge base, "
        "launcher, resource monitor, observers, diagnosis and repair rules, task executor "
        "and goal planner. Goals come with 'dura goal add'; the task executor starts the "
        "components each task needs. Ctrl-C or SIGTERM stops every component and then the "
        "executive.",
    )
    p.add_argument("robot", metavar="ROBOT.yaml", type=Path, help="the robot description")
    p.add_argument("--endpoint", help="listen here instead of the robot's bus endpoint")
    p.add_argument("--db", type=Path, help="the knowledge base file (default: the robot's)")
    add_launcher_options(p, resources="how often the resource monitor publishes")
    p.add_argument(
        "--linger",
        type=seconds(),
        default=0.0,
        metavar="SECONDS",
        help="keep a functionality running this long after no task and no upcoming plan "
        "step needs it (default 0: stop it then)",
    )
    p.add_argument(
        "--starts",
        choices=("parallel", "sequential"),
        default="parallel",
        help="how a configuration changes: parallel (default) starts the new components "
        "all at once before the old ones stop; sequential stops first, then starts one "
        "after another in dependency order",
    )
    p.add_argument(
        "--dashboard",
        type=port,
        metavar="PORT",
        help="also serve the live dashboard on this port (see 'dura dashboard --help')",
    )
    add_dashboard_address(p, "dashboard-")
    p.add_argument(
        "--record",
        type=Path,
        metavar="OUT.mcap",
        help="record the robot's bus traffic to MCAP, as 'dura record' does",
    )
    p.add_argument(
        "--record-max-size",
        type=megabytes,
        metavar="MB",
        help="rotate the recording at this size (default 100)",
    )
    p.add_argument(
        "--record-flush",
        type=seconds(),
        metavar="S",
        help="write the recording as a whole chunk at least every S seconds (default 1)",
    )
    split = p.add_mutually_exclusive_group()
    split.add_argument(
        "--only",
        choices=SEPARABLE,
        help="run only this group of services, in this process, connected to the executive "
        "at --endpoint (which runs with --without GROUP); it waits for the executive",
    )
    split.add_argument(
        "--without",
        choices=SEPARABLE,
        action="append",
        default=[],
        help="run the executive without this group of services (another process runs them "
        "with --only GROUP); may be given more than once",
    )
    shown = p.add_mutually_exclusive_group()
    shown.add_argument(
        "--quiet",
        "-q",
        action="store_true",
        help="print no live log on a terminal (only the first and the last line)",
    )
    shown.add_argument(
        "--log",
        action="store_true",
        help="print the live log (plans, steps, faults, repairs, goals and warnings, one "
        "line each) also when the output is not a terminal",
    )
    add_json_flag(p)
    p.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    limit_arenas()  # before any thread starts (see executive.runtime.native_heap)
    with HeapTrimmer():
        return _run(args)


def _run(args: argparse.Namespace) -> int:
    robot = load_robot(args.robot, domain=False)  # the planner worker checks the domain
    stop = stop_on_signals()
    failure: list[str] = []

    def failed(reason: str) -> None:
        failure.append(reason)
        stop.set()

    if args.only is not None:
        return run_only(args, robot, stop)
    executive = Executive(
        robot,
        endpoint=args.endpoint,
        kb_path=args.db,
        log_dir=args.log_dir.resolve(),
        resource_rate=args.resource_rate,
        grace=args.grace,
        linger=args.linger,
        sequential_starts=args.starts == "sequential",
        record=args.record.resolve() if args.record is not None else None,
        record_max_size=args.record_max_size,
        record_flush=args.record_flush,
        on_failure=failed,
        without=args.without,
    )
    endpoint = local_endpoint(executive.endpoint)
    executive.on_open = lambda: write_run_file(
        robot.name, endpoint, robot.path, executive.credentials_path
    )
    with contextlib.ExitStack() as running:
        running.callback(remove_run_file)  # last, also when the executive fails to start
        with LiveLine(shown=not args.json) as line:
            executive.progress = line.doing
            running.enter_context(executive)
        url = None
        if args.dashboard is not None:
            from executive.dashboard.server import Dashboard  # the web stack, if asked

            page = Dashboard.connect(robot, endpoint, host=args.dashboard_host,
                                     port=args.dashboard,
                                     allow=tuple(args.dashboard_allow_host))  # fmt: skip
            url = running.enter_context(page).url
        if args.json:
            print_json({"robot": robot.name, "endpoint": endpoint, "pid": os.getpid(),
                        **({"dashboard": url} if url else {})})  # fmt: skip
        else:
            print(
                f"dura: executive of robot '{robot.name}' runs on {endpoint} (pid "
                f"{os.getpid()}, knowledge base {shown(executive.kb_path)}); Ctrl-C stops it"
            )
            if url:
                print(f"dura: dashboard on {url}")
        sys.stdout.flush()
        if not args.json and not args.quiet and (args.log or sys.stdout.isatty()):
            running.enter_context(live_log(executive, args.verbose))
        wait(stop)
    if failure:
        print(f"dura: {failure[0]}", file=sys.stderr)
        return 1
    if not args.json:
        print(f"dura: executive of robot '{robot.name}' stopped")
    return 0


@contextlib.contextmanager
def live_log(executive: Executive, verbose: int) -> Iterator[None]:
    """Print what the robot does, as ``dura demo`` does, while the block runs: a line for
    each event that matters and each diagnosis, a timeline for each plan, and the
    process's warnings as lines of the same format (instead of Python's log lines)."""
    timeline = Timeline(quiet=False, everything=False)
    timeline.use(executive.kb_path)
    root = logging.getLogger()
    handlers = list(root.handlers)
    if not verbose:  # -v keeps Python's log lines, for the detail they add
        for handler in handlers:
            root.removeHandler(handler)
    warnings = WarningLines(timeline)
    root.addHandler(warnings)
    subscriptions = [
        executive.bus.subscribe(EVENTS, timeline.on_event),
        executive.bus.subscribe(DIAGNOSES, timeline.on_diagnoses),
    ]
    try:
        timeline.doing("waiting for goals (dura goal add)")
        yield
    finally:
        for subscription in subscriptions:
            with contextlib.suppress(Exception):
                subscription.undeclare()
        timeline.close()
        root.removeHandler(warnings)
        for handler in handlers:
            if handler not in root.handlers:
                root.addHandler(handler)


def run_only(args: argparse.Namespace, robot: RobotDescription, stop: threading.Event) -> int:
    """``--only GROUP``: those services in this process, until Ctrl-C or SIGTERM."""
    endpoint = local_endpoint(args.endpoint or robot.endpoint)

    def say(line: str) -> None:
        if args.json:
            print_json({"robot": robot.name, "only": args.only, "event": line})
        else:
            print(f"dura: {args.only} of robot '{robot.name}': {line}")
        sys.stdout.flush()

    services = ServiceProcess(
        robot,
        args.only,
        endpoint=endpoint,
        kb_path=args.db,
        say=say,
        log_dir=args.log_dir.resolve(),
        resource_rate=args.resource_rate,
        grace=args.grace,
        linger=args.linger,
        sequential_starts=args.starts == "sequential",
    )
    say(f"connects to {endpoint}; Ctrl-C stops it")
    services.run(stop)
    say("stopped")
    return 0
