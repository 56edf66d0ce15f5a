"""``dura observer list|add|change|remove|activate|deactivate|exonerate``: a running robot's
observers, and how its diagnosis reads their OK observations, changed while it runs."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

from executive.bus.api import monitoring as api
from executive.bus.schema import plain
from executive.bus.verb import Verb
from executive.cli import exits_at_once
from executive.cli.client import add_client_options, ask, connect
from executive.cli.output import add_json_flag, print_json, shown, table
from knowledge.errors import DuraError

EXONERATION = {
    True: "on: an OK topic observation means its topics are not abnormal",
    False: "off: OK observations clear nothing (the thesis' model)",
}


def register(sub: Any) -> None:
    p = sub.add_parser(
        "observer",
        help="change observers at run time (list, add, remove, ...); switch exoneration",
        description="Change the observers of a running robot (its observer manager) without "
        "restarting it. Observer ids are '<component>/<index>' for those of the robot "
        "description. An observer observes while it is activated and its component is ready.",
    )
    exits_at_once(p)
    osub = p.add_subparsers(dest="observer_command", metavar="OBSERVER_COMMAND")
    osub.required = True

    listing = osub.add_parser("list", help="every observer: type, component, activated, observing")
    listing.set_defaults(run=run_list)

    add = osub.add_parser(
        "add",
        help="add the observers of a file (the tug form: a list, or 'setup: [...]')",
        description="Check every observer of FILE (a list of observers in the thesis/tug "
        "schema, or 'setup: [...]'; each problem as FILE:line: message) and add them all, "
        "or none: an observer the executive refuses takes back those added before it.",
    )
    add.add_argument("file", metavar="FILE", type=Path, help="the observers file")
    add.add_argument(
        "--component",
        metavar="NAME",
        help="whose observers they are: they observe only while NAME is ready",
    )
    add.add_argument("--name", metavar="ID", help="the id of the (single) observer")
    add.set_defaults(run=run_add, parser=add)

    change = osub.add_parser(
        "change", help="replace an observer's configuration (one observer in FILE)"
    )
    change.add_argument("id", metavar="ID")
    change.add_argument("file", metavar="FILE", type=Path, help="an observers file of one")
    change.set_defaults(run=run_change)

    commands = [listing, add, change]
    for verb, text in (
        ("remove", "remove an observer"),
        ("activate", "let an observer observe (while its component is ready)"),
        ("deactivate", "stop an observer until it is activated again"),
    ):
        cmd = osub.add_parser(verb, help=text)
        cmd.add_argument("id", metavar="ID")
        cmd.set_defaults(run=run_switch, verb=verb)
        commands.append(cmd)

    exonerate = osub.add_parser(
        "exonerate",
        help="whether OK observations clear topics in the diagnosis (on|off; none: show)",
        description="Switch exoneration of the running diagnosis engine: on, an OK topic "
        "observation means its topics are not abnormal (fewer, sharper diagnoses when "
        "observers can be trusted); off, OK observations clear nothing (the thesis' model, "
        "the default). The diagnosis is computed again at once; the switch lasts until the "
        "executive stops. Without on|off, print the setting.",
    )
    exonerate.add_argument("setting", nargs="?", choices=["on", "off"])
    exonerate.set_defaults(run=run_exonerate)
    commands.append(exonerate)

    for cmd in commands:
        add_client_options(cmd)
        add_json_flag(cmd)


def run_list(args: argparse.Namespace) -> int:
    observers = ask(args, api.OBSERVER_LIST).observers
    if args.json:
        print_json({"observers": plain(observers)})
        return 0
    table(
        ["id", "type", "component", "activated", "observing", "rate", "start-up"],
        [
            [o.id, o.type, o.component, o.enabled, o.active, f"{o.main_loop_rate:g} Hz",
             f"{o.start_up_time:g} s"]
            for o in observers
        ],
    )  # fmt: skip
    return 0


def _entries(path: Path) -> list[tuple[int, dict[str, Any]]]:
    """The observers of a file with their lines, each checked as the executive will.

    Raises:
        DuraError: the file is no observers file, or an observer has problems (all of
            them, one per line).
    """
    from monitoring.observer_config import check_observer_file  # YAML and observer types

    checked = check_observer_file(path)
    if checked is None:
        raise DuraError(
            f"{shown(path)}: not an observers file (a list of observers, or 'setup: [...]')"
        )
    specs, findings = checked
    errors = [f for f in findings if f.is_error]
    if errors:
        raise DuraError("\n".join(str(f) for f in errors))
    if not specs:
        raise DuraError(f"{shown(path)}: no observers in the file")
    return [(spec.line, dict(spec.config)) for spec in specs]


def _reason(error: DuraError, verb: str) -> str:
    """The executive's reason, without the key it was asked on."""
    return str(error).removeprefix(f"{verb}: ")


def run_add(args: argparse.Namespace) -> int:
    entries = _entries(args.file)
    if args.name is not None and len(entries) > 1:
        args.parser.error(f"--name names one observer; {shown(args.file)} has {len(entries)}")
    added: list[api.ObserverActive] = []
    with connect(args) as bus:
        for line, config in entries:
            request = api.ObserverAdd(config, args.component, args.name)
            try:
                added.append(api.OBSERVER_ADD.call(bus, request))
            except DuraError as e:
                for done in reversed(added):  # all or nothing
                    api.OBSERVER_REMOVE.call(bus, api.ObserverId(done.id))
                where = f"{shown(args.file)}:{line}" if line else shown(args.file)
                kept = f"; {len(added)} added before it taken back" if added else ""
                raise DuraError(f"{where}: {_reason(e, api.OBSERVER_ADD.key)}{kept}") from e
    if args.json:
        print_json({"observers": [a.to_payload() for a in added]})
        return 0
    for (_, config), reply in zip(entries, added, strict=True):
        print(f"{reply.id}: {config.get('type')} observer added ({_observing(reply, args)})")
    return 0


def _observing(reply: api.ObserverActive, args: argparse.Namespace) -> str:
    if reply.active:
        return "observing"
    owner = getattr(args, "component", None) or reply.id.rpartition("/")[0]
    return f"observes once {owner} is ready"


def run_change(args: argparse.Namespace) -> int:
    entries = _entries(args.file)
    if len(entries) != 1:
        raise DuraError(f"{shown(args.file)}: {len(entries)} observers; change takes one")
    try:
        reply = ask(args, api.OBSERVER_CHANGE, api.ObserverChange(args.id, entries[0][1]))
    except DuraError as e:
        raise DuraError(_reason(e, api.OBSERVER_CHANGE.key)) from e
    if args.json:
        print_json(reply.to_payload())
    else:
        print(f"{reply.id}: changed, starts afresh ({_observing(reply, args)})")
    return 0


def run_switch(args: argparse.Namespace) -> int:
    verbs: dict[str, Verb[api.ObserverId, Any]] = {
        "remove": api.OBSERVER_REMOVE,
        "activate": api.OBSERVER_ACTIVATE,
        "deactivate": api.OBSERVER_DEACTIVATE,
    }
    verb = verbs[args.verb]
    try:
        reply = ask(args, verb, api.ObserverId(args.id))
    except DuraError as e:
        raise DuraError(_reason(e, verb.key)) from e
    if args.json:
        print_json(reply.to_payload())
    elif isinstance(reply, api.ObserverActive) and args.verb == "activate":
        print(f"{reply.id}: activated ({_observing(reply, args)})")
    else:
        print(f"{reply.id}: {args.verb}d")
    return 0


def run_exonerate(args: argparse.Namespace) -> int:
    on = None if args.setting is None else args.setting == "on"
    reply = ask(args, api.DIAGNOSIS_EXONERATE, api.ExonerationChange(on))
    if args.json:
        print_json(reply.to_payload())
    else:
        print(f"exoneration {EXONERATION[reply.on]}")
    return 0
