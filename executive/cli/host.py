"""``dura host ROBOT.yaml --name NAME``: the host agent of one of the robot's computers."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Any

from executive.cli.arguments import add_launcher_options, seconds
from executive.cli.output import add_json_flag, print_json
from executive.cli.stopping import stop_on_signals


def register(sub: Any) -> None:
    p = sub.add_parser(
        "host",
        help="run the host agent of one of the robot's computers in the foreground",
        description="Run the host agent of a computer of the robot: it connects to the "
        "executive's bus with the host's credentials, starts, stops and reaps the components "
        "the robot description places on this host (host: NAME), keeps their logs here and "
        "measures their resources. When the executive is lost it ends them, and it joins "
        "again when the executive is back. Ctrl-C or SIGTERM ends the components and the agent.",
    )
    p.add_argument("robot", metavar="ROBOT.yaml", type=Path, help="the robot description")
    p.add_argument("--name", required=True, help="this host's name in the robot description")
    p.add_argument(
        "--connect",
        metavar="ENDPOINT",
        help="the executive's endpoint as this computer reaches it, e.g. "
        "tcp/192.168.1.10:7447 (default: the robot's bus endpoint)",
    )
    p.add_argument(
        "--credentials",
        type=Path,
        metavar="FILE",
        help="the host's credentials file (default: .dura/ROBOT.NAME.bus.json, then "
        ".dura/ROBOT.bus.json)",
    )
    add_launcher_options(
        p, resources="how often the resources of this host's components are published"
    )
    p.add_argument(
        "--lease",
        type=seconds(),
        default=3.0,
        metavar="SECONDS",
        help="silence after which the link to the executive counts as lost (default 3)",
    )
    add_json_flag(p)
    p.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    """The agent's process: its bus login, its launcher and the resource monitor of its
    own processes, composed here (as :mod:`executive.executive` composes the
    executive's)."""
    # the agent's parts load only for `dura host` (`dura --help` imports every command)
    from executive.bus import security
    from executive.bus.keys import host
    from executive.bus.session import Bus
    from executive.runtime.host_agent import HostAgent
    from executive.runtime.launcher import local_endpoint
    from knowledge.robot import load_robot
    from monitoring.resource_monitor import HOST_RESOURCES, ResourceSampler

    robot = load_robot(args.robot)
    endpoint = args.connect or local_endpoint(robot.endpoint)
    stop = stop_on_signals()

    def say(line: str) -> None:
        if args.json:
            print_json({"host": args.name, "event": line})
        else:
            print(f"dura: host '{args.name}': {line}")
        sys.stdout.flush()

    placed = ", ".join(robot.placed_on(args.name)) or "nothing"
    say(f"agent of robot '{robot.name}' connects to {endpoint} for {placed}; Ctrl-C stops it")
    # raises BusError without usable credentials for the host
    login = security.find_host_login(robot.name, args.name, Path.cwd(), args.credentials)

    def sampler(bus: Bus) -> ResourceSampler:
        return ResourceSampler(
            bus, rate=args.resource_rate, hostname=args.name, key=host(args.name, HOST_RESOURCES)
        )

    agent = HostAgent(
        robot,
        args.name,
        endpoint=endpoint,
        login=login,
        log_dir=args.log_dir.resolve(),
        grace=args.grace,
        tracker=sampler,
        lease=args.lease,
        say=say,
    )
    agent.run(stop)
    say("stopped")
    return 0
