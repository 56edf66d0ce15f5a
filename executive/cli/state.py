"""``dura state get|set|unset``: the facts the planner plans from, in a running robot's
knowledge base."""

from __future__ import annotations

import argparse
from typing import Any

from executive.bus.api import planning as api
from executive.bus.schema import plain
from executive.cli import exits_at_once
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
        cmd.set_defaults(run=run_change, verb=verb)
    for cmd in ssub.choices.values():
        add_client_options(cmd)
        add_json_flag(cmd)


def _value(fact: Fact) -> str:
    return "true" if fact.value is True else f"{fact.value:g}"


def run_get(args: argparse.Namespace) -> int:
    reply = ask(args, api.STATE_GET, api.StateQuery(args.pattern))
    if args.json:
        print_json(reply.to_payload())
        return 0
    table(
        ["fact", "value"],
        [[f"({' '.join([f.name, *f.args])})", _value(f)] for f in reply.facts],
    )
    return 0


def run_change(args: argparse.Namespace) -> int:
    verb = api.STATE_UNSET if args.verb == "unset" else api.STATE_SET
    fact = ask(args, verb, api.FactChange(args.fact)).fact
    if args.json:
        print_json(plain(fact))
    else:
        print(f"{fact.text} {'unset' if args.verb == 'unset' else 'set'}")
    return 0
