"""``dura param get|set|list COMPONENT [KEY] [VALUE]``: a component's parameters in a
running robot's knowledge base; a running component takes a change at once."""

from __future__ import annotations

import argparse
import json
from typing import Any

from executive.bus.api.parameters import (
    PARAMETER_GET,
    PARAMETER_LIST,
    PARAMETER_SET,
    ComponentParameters,
    ParameterChange,
    ParameterKey,
)
from executive.cli import exits_at_once
from executive.cli.client import add_client_options, ask
from executive.cli.output import add_json_flag, print_json, table


def register(sub: Any) -> None:
    p = sub.add_parser(
        "param",
        help="read and change component parameters at run time",
        description="Read and change a component's parameters. A change is checked against "
        "the type the robot description gives the parameter, stored in the knowledge base "
        "(it overrides the description), and handed to the running component: through its "
        "on_reconfigure hook, or by a warm restart for a component without one.",
    )
    exits_at_once(p)
    psub = p.add_subparsers(dest="param_command", metavar="PARAM_COMMAND")
    psub.required = True
    listing = psub.add_parser("list", help="every parameter of a component, with its source")
    listing.add_argument("component", metavar="COMPONENT")
    listing.set_defaults(run=run_list)
    get = psub.add_parser("get", help="one parameter of a component")
    get.add_argument("component", metavar="COMPONENT")
    get.add_argument("key", metavar="KEY")
    get.set_defaults(run=run_get)
    change = psub.add_parser(
        "set",
        help="change a parameter of a component",
        description="Set KEY of COMPONENT to VALUE, read as JSON (5, 2.5, true, "
        '"text", [1, 2]); anything that is not JSON is a string.',
    )
    change.add_argument("component", metavar="COMPONENT")
    change.add_argument("key", metavar="KEY")
    change.add_argument("value", metavar="VALUE")
    change.set_defaults(run=run_set)
    for cmd in (listing, get, change):
        add_client_options(cmd)
        add_json_flag(cmd)


def value_of(text: str) -> Any:
    """A command-line value: JSON if it is JSON, else the text itself."""
    try:
        return json.loads(text)
    except ValueError:
        return text


def run_list(args: argparse.Namespace) -> int:
    reply = ask(args, PARAMETER_LIST, ComponentParameters(args.component))
    if args.json:
        print_json(reply.to_payload())
        return 0
    rows = [[k, json.dumps(v), reply.sources[k]] for k, v in reply.parameters.items()]
    table(["key", "value", "source"], rows)
    return 0


def run_get(args: argparse.Namespace) -> int:
    reply = ask(args, PARAMETER_GET, ParameterKey(args.component, args.key))
    if args.json:
        print_json(reply.to_payload())
    else:
        print(json.dumps(reply.value))
    return 0


def run_set(args: argparse.Namespace) -> int:
    change = ParameterChange(args.component, args.key, value_of(args.value))
    reply = ask(args, PARAMETER_SET, change)
    if args.json:
        print_json(reply.to_payload())
        return 0
    how = {
        "reconfigured": "the running component took it",
        "restarted": "the component was restarted with it",
        "stored": "it takes effect at the component's next start",
    }.get(reply.applied, reply.applied)
    print(f"{reply.component}.{reply.key} = {json.dumps(reply.value)}: {how}")
    return 0
