"""``dura state get|set|unset`` and ``dura object add|remove``: the facts and objects the
planner plans from, in a running robot's knowledge base."""

from __future__ import annotations

import argparse
from typing import Any

from executive.bus.api import planning as api
from executive.bus.wording import plural
from executive.cli import exits_at_once
from executive.cli.client import add_client_options, ask
from executive.cli.output import add_json_flag, print_json, table


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
    cmds = [get, *ssub.choices.values()]

    o = sub.add_parser("object", help="add and remove PDDL objects of a running robot's world")
    exits_at_once(o)
    osub = o.add_subparsers(dest="object_command", metavar="OBJECT_COMMAND")
    osub.required = True
    add = osub.add_parser("add", help="add an object of a domain type")
    add.add_argument("name", metavar="NAME", help="the object's name (a PDDL name)")
    add.add_argument("type", metavar="TYPE", help="one of the domain's types")
    add.set_defaults(run=run_object_add)
    remove = osub.add_parser(
        "remove",
        help="remove an object and every fact that names it",
        description="Remove an object from the world, with every fact that names it (as "
        "PlanSys2 removes an instance). Refused, with the reason, while an open goal, the "
        "current plan or an integrity rule names it: cancel the goal or change the rule "
        "first.",
    )
    remove.add_argument("name", metavar="NAME")
    remove.set_defaults(run=run_object_remove)
    for cmd in {*cmds, add, remove}:
        add_client_options(cmd)
        add_json_flag(cmd)


def _value(fact: dict[str, Any]) -> str:
    value = fact["value"]
    return "true" if value is True else f"{value:g}"


def run_get(args: argparse.Namespace) -> int:
    reply = ask(args, api.STATE_GET, api.StateQuery(args.pattern))
    if args.json:
        print_json(reply.to_payload())
        return 0
    table(
        ["fact", "value"],
        [[f"({' '.join([f['name'], *f['args']])})", _value(f)] for f in reply.facts],
    )
    return 0


def run_change(args: argparse.Namespace) -> int:
    verb = api.STATE_UNSET if args.verb == "unset" else api.STATE_SET
    fact = ask(args, verb, api.FactChange(args.fact)).fact
    if args.json:
        print_json(fact)
    else:
        print(f"{fact['text']} {'unset' if args.verb == 'unset' else 'set'}")
    return 0


def run_object_add(args: argparse.Namespace) -> int:
    added = ask(args, api.OBJECT_ADD, api.ObjectAdd(args.name, args.type))
    if args.json:
        print_json(added.to_payload())
    else:
        print(f"object {added.name} - {added.type} added")
    return 0


def run_object_remove(args: argparse.Namespace) -> int:
    removed = ask(args, api.OBJECT_REMOVE, api.ObjectName(args.name))
    if args.json:
        print_json(removed.to_payload())
        return 0
    ((name, type_name),) = removed.objects.items()
    facts = [f["text"] for f in removed.facts]
    also = f", and {plural(len(facts), 'fact')}: {', '.join(facts)}" if facts else ""
    print(f"object {name} - {type_name} removed{also}")
    return 0
