"""``dura state get|set|unset``: the facts the planner plans from, in a running robot's
knowledge base."""

from __future__ import annotations

import argparse
import time
from typing import Any

from executive.bus.api import planning as api
from executive.bus.schema import plain
from executive.cli import exits_at_once
from executive.cli.arguments import moment
from executive.cli.client import add_client_options, ask
from executive.cli.output import add_json_flag, print_json, table
from knowledge.records import Fact


def register(sub: Any) -> None:
    p = sub.add_parser("state", help="read and change the facts the planner plans from")
    exits_at_once(p)
    ssub = p.add_subparsers(dest="state_command", metavar="STATE_COMMAND")
    ssub.required = True
    get = ssub.add_parser(
        "get",
        help="the facts, all or those matching a pattern",
        description="Print the facts. PATTERN is a predicate or function name with leading "
        "arguments, '*' for any: 'robot_at', '(robot_at *)', '(travel_time dock *)'.",
    )
    get.add_argument(
        "pattern", nargs="?", default="", metavar="PATTERN", help="a predicate and arguments"
    )
    get.set_defaults(run=run_get)
    for verb, text in (
        ("set", "make a fact true: '(robot_at lab)', or set a value: '(= (battery) 80)'"),
        ("unset", "make a fact false: '(robot_at lab)'"),
    ):
        cmd = ssub.add_parser(verb, help=text)
        cmd.add_argument(
            "fact", metavar="FACT", help="a fact in PDDL: '(robot_at lab)' or '(= (battery) 80)'"
        )
        cmd.add_argument(
            "--at",
            type=moment,
            metavar="TIME",
            help="not now but at TIME (14:00, 14:00:30, +90 for seconds from now, or "
            "2026-11-27T14:00): the planner plans with it from now on, and it takes effect "
            "then ('the door opens at 14:00')",
        )
        cmd.set_defaults(run=run_change, verb=verb)
    for cmd in ssub.choices.values():
        add_client_options(cmd)
        add_json_flag(cmd)


def _value(fact: Fact) -> str:
    if isinstance(fact.value, bool):
        return str(fact.value).lower()
    return f"{fact.value:g}"


def run_get(args: argparse.Namespace) -> int:
    reply = ask(args, api.STATE_GET, api.StateQuery(args.pattern))
    if args.json:
        print_json(reply.to_payload())
        return 0
    table(
        ["fact", "value"],
        [[f"({' '.join([f.name, *f.args])})", _value(f)] for f in reply.facts],
    )
    if reply.timed:
        print()
        table(
            ["later", "fact", "value"],
            [[_when(t.at), f"({' '.join([t.fact.name, *t.fact.args])})", _value(t.fact)]
             for t in reply.timed],
        )  # fmt: skip
    return 0


def _when(at: float) -> str:
    return time.strftime("%Y-%m-%d %H:%M:%S", time.localtime(at))


def run_change(args: argparse.Namespace) -> int:
    verb = api.STATE_UNSET if args.verb == "unset" else api.STATE_SET
    reply = ask(args, verb, api.FactChange(args.fact, at=args.at))
    fact = reply.fact
    if args.json:
        print_json(plain(fact) if reply.at is None else plain(reply))
    elif reply.at is not None:
        print(f"{fact.text} from {_when(reply.at)} on")
    else:
        print(f"{fact.text} {'unset' if args.verb == 'unset' else 'set'}")
    return 0
