"""``dura goal add|list|show|cancel``: the goal submission interface of a running robot."""

from __future__ import annotations

import argparse
import time
from typing import Any

from executive.bus.api import planning as api
from executive.cli.arguments import identifier, priority, seconds
from executive.cli.client import add_client_options, ask
from executive.cli.output import add_json_flag, print_json, table
from knowledge.lifecycle import GoalState


def register(sub: Any) -> None:
    p = sub.add_parser("goal", help="submit, list, show and cancel goals")
    gsub = p.add_subparsers(dest="goal_command", metavar="GOAL_COMMAND")
    gsub.required = True

    add = gsub.add_parser(
        "add",
        help="submit a goal: a PDDL goal expression",
        description="Submit a PDDL goal expression, e.g. '(picture_taken lab)' or "
        "'(and (robot_at dock) (picture_taken office))'. A goal naming unknown predicates "
        "or objects is refused with the reason.",
    )
    add.add_argument("expression", metavar="EXPR", help="the goal expression")
    add.add_argument(
        "--deadline", type=seconds(), metavar="S", help="seconds from now by which it must hold"
    )
    add.add_argument(
        "--priority", type=priority, default=0, metavar="P", help="higher goals win (default 0)"
    )
    add.set_defaults(run=run_add)

    listing = gsub.add_parser("list", help="every goal with its state")
    listing.add_argument(
        "--open", action="store_true", help="only goals not yet achieved, failed or cancelled"
    )
    listing.set_defaults(run=run_list)

    show = gsub.add_parser("show", help="one goal and its history")
    show.add_argument("id", type=identifier, metavar="ID", help="the goal's id")
    show.set_defaults(run=run_show)

    cancel = gsub.add_parser("cancel", help="cancel an open goal (the others are replanned)")
    cancel.add_argument("id", type=identifier, metavar="ID", help="the goal's id")
    cancel.set_defaults(run=run_cancel)

    for cmd in (add, listing, show, cancel):
        add_client_options(cmd)
        add_json_flag(cmd)


def clock(stamp: float) -> str:
    return time.strftime("%H:%M:%S", time.localtime(stamp)) if stamp else "-"


def goal_rows(goals: list[dict[str, Any]]) -> list[list[Any]]:
    return [
        [
            g["id"],
            g["state"],
            g["priority"],
            "-" if g["deadline"] is None else f"{g['deadline']:g} s",
            g["source"],
            g["expression"],
            g["reason"],
        ]
        for g in goals
    ]


GOAL_HEADERS = ["id", "state", "priority", "deadline", "source", "goal", "reason"]


def run_add(args: argparse.Namespace) -> int:
    request = api.GoalAdd(args.expression, args.priority, args.deadline)
    goal = ask(args, api.GOAL_ADD, request).goal
    if args.json:
        print_json(goal)
    else:
        print(f"goal {goal['id']}: {goal['expression']} ({goal['state']})")
    return 0


def run_list(args: argparse.Namespace) -> int:
    states = [s for s in GoalState if s.is_open] if args.open else None
    goals = ask(args, api.GOAL_LIST, api.GoalQuery(states)).goals
    if args.json:
        print_json({"goals": goals})
    else:
        table(GOAL_HEADERS, goal_rows(goals))
    return 0


def run_show(args: argparse.Namespace) -> int:
    reply = ask(args, api.GOAL_SHOW, api.GoalId(args.id))
    if args.json:
        print_json(reply.to_payload())
        return 0
    g = reply.goal
    print(f"goal {g['id']}: {g['expression']}")
    print(f"  state {g['state']}{': ' + g['reason'] if g['reason'] else ''}")
    deadline = "none" if g["deadline"] is None else f"{g['deadline']:g} s after submission"
    print(f"  priority {g['priority']}, deadline {deadline}, from {g['source']}")
    print(f"  submitted {clock(g['created'])}, last change {clock(g['updated'])}")
    if reply.events:
        print()
        table(
            ["time", "event", "details"],
            [[clock(e["stamp"]), e["kind"], details(e["data"])] for e in reply.events],
        )
    return 0


def run_cancel(args: argparse.Namespace) -> int:
    goal = ask(args, api.GOAL_CANCEL, api.GoalId(args.id)).goal
    if args.json:
        print_json(goal)
    else:
        print(f"goal {goal['id']}: {goal['state']}")
    return 0


def details(data: Any) -> str:
    """An event's data on one line: ``key value, key value``."""
    if not isinstance(data, dict):
        return str(data)
    shown = {k: v for k, v in data.items() if v not in (None, "", [], {}) and k != "stamp"}
    return ", ".join(f"{k} {v}" for k, v in shown.items())
