"""``dura dashboard``: the live web page of a running robot."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

from executive.cli.client import run_file
from executive.cli.stopping import stop_on_signals, wait
from executive.dashboard.access import DEFAULT_HOST, DEFAULT_PORT
from knowledge.description import RobotDescription
from knowledge.robot import load_robot


def add_dashboard_address(parser: Any, prefix: str = "") -> None:
    """``--host`` and ``--port`` (``--dashboard-host`` with a prefix)."""
    parser.add_argument(
        f"--{prefix}host",
        default=DEFAULT_HOST,
        metavar="HOST",
        help=f"the address the page listens on (default {DEFAULT_HOST}, this machine only; "
        "any other needs the robot's bus credentials: visitors log in as 'operator')",
    )
    parser.add_argument(
        f"--{prefix}allow-host",
        action="append",
        default=[],
        metavar="NAME",
        help="a host name visitors may call the page by (repeatable; default: loopback "
        "names, IP addresses and, beyond loopback, this machine's names): a page reached by "
        "another name is refused (DNS rebinding)",
    )


def port(text: str) -> int:
    """A TCP port: 0 (a free one) to 65535."""
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"'{text}' is not a port number") from None
    if not 0 <= value <= 65535:
        raise argparse.ArgumentTypeError(f"must be a port from 0 to 65535, not {text}")
    return value


def register(sub: Any) -> None:
    p = sub.add_parser(
        "dashboard",
        help="serve a live web page of the running robot",
        description="Serve the dashboard of a running robot: goals (add and cancel them), the "
        "plan as a Gantt chart with live progress, the component graph coloured by state with "
        "the diagnoses, the observations with their recent values, and the event log, updated "
        "live. It listens on 127.0.0.1 by default; only visitors with the robot's bus "
        "credentials get in, from this machine too (the link printed at start, or HTTP basic "
        "authentication as 'operator'). Ctrl-C stops it.",
    )
    p.add_argument(
        "--robot",
        metavar="ROBOT.yaml",
        type=Path,
        help="the robot whose executive to show (default: the one 'dura run' runs in this folder)",
    )
    p.add_argument("--endpoint", help="where that executive listens (default: the robot's)")
    add_dashboard_address(p)
    p.add_argument(
        "--port",
        type=port,
        default=DEFAULT_PORT,
        metavar="PORT",
        help=f"the page's port (default {DEFAULT_PORT}; 0: any free one)",
    )
    p.set_defaults(run=run)


def _described(path: Path) -> RobotDescription:
    """A robot description, or a fleet's (``dura fleet run``): its high level is shown."""
    from executive.fleet.description import is_fleet_file, load_fleet

    return load_fleet(path).as_robot() if is_fleet_file(path) else load_robot(path)


def target(args: argparse.Namespace) -> tuple[RobotDescription, str]:
    """The robot description and the endpoint of the executive to show."""
    if args.robot is not None:
        robot = _described(args.robot)
        return robot, args.endpoint or robot.endpoint
    found = run_file("description", "endpoint")
    description, endpoint = Path(found["description"]), str(found["endpoint"])
    return _described(description), args.endpoint or endpoint


def run(args: argparse.Namespace) -> int:
    from executive.dashboard.server import Dashboard  # the web stack loads only when needed
    from executive.fleet.description import is_fleet_file

    robot, endpoint = target(args)
    stop = stop_on_signals()
    allow = tuple(args.allow_host)
    fleet = is_fleet_file(robot.path)
    with Dashboard.connect(
        robot, endpoint, host=args.host, port=args.port, allow=allow, fleet=fleet
    ) as dashboard:
        print(
            f"dura: dashboard of robot '{robot.name}' on {dashboard.url} (executive at "
            f"{endpoint}); Ctrl-C stops it",
            flush=True,
        )
        wait(stop)
    print("dura: dashboard stopped")
    return 0
