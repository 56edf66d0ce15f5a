"""``dura object add|remove``: the PDDL objects of a running robot's world."""

from __future__ import annotations

import argparse
from typing import Any

from executive.bus.api import planning as api
from executive.bus.wording import plural
from executive.cli import exits_at_once
from executive.cli.client import add_client_options, ask
from executive.cli.output import add_json_flag, print_json


def register(sub: Any) -> None:
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
    for cmd in (add, remove):
        add_client_options(cmd)
        add_json_flag(cmd)


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
    facts = [f.text for f in removed.facts]
    also = f", and {plural(len(facts), 'fact')}: {', '.join(facts)}" if facts else ""
    print(f"object {name} - {type_name} removed{also}")
    return 0
