"""``dura goal add|list|show|cancel``: the goal submission interface of a running robot."""

from __future__ import annotations

import argparse
import time
from typing import Any

from executive.bus.api import planning as api
from executive.cli.arguments import identifier, priority, seconds
from executive.cli.client import add_client_options, ask
from executive.cli.output import add_json_flag, print_json, table
from knowledge.records import GoalState


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
    add.add_argument(
        "--keep",
        action="store_true",
        help="a maintenance goal: once achieved it is watched, and posted again whenever it "
        "stops holding",
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


def state_of(goal: dict[str, Any]) -> str:
    """A goal's state as shown: a maintenance goal that is achieved is watched."""
    if goal.get("keep") and goal["state"] == GoalState.ACHIEVED.value:
        return "achieved, watched"
    return str(goal["state"])


def goal_rows(goals: list[dict[str, Any]]) -> list[list[Any]]:
    return [
        [
            g["id"],
            state_of(g),
            "keep" if g.get("keep") else "once",
            g["priority"],
            "-" if g["deadline"] is None else f"{g['deadline']:g} s",
            g["source"],
            g["expression"],
            g["reason"],
        ]
        for g in goals
    ]


GOAL_HEADERS = ["id", "state", "kind", "priority", "deadline", "source", "goal", "reason"]

MEANING = {
    "achieved": "it held when the executive checked it, at {updated}; it is not watched "
    "since (a goal added with --keep is)",
    "achieved, watched": "a maintenance goal: it held when last checked, at {updated}; it is "
    "watched and posted again whenever it stops holding",
    "unreachable": "no plan reached it; it is looked at again when the world changes (a fact "
    "or object set, a component reset or repaired)",
}


def run_add(args: argparse.Namespace) -> int:
    request = api.GoalAdd(args.expression, args.priority, args.deadline, keep=args.keep)
    goal = ask(args, api.GOAL_ADD, request).goal
    if args.json:
        print_json(goal)
    else:
        kept = ", kept" if goal.get("keep") else ""
        print(f"goal {goal['id']}: {goal['expression']} ({goal['state']}{kept})")
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
    kind = "maintenance goal" if g.get("keep") else "goal"
    print(f"{kind} {g['id']}: {g['expression']}")
    state = state_of(g)
    print(f"  state {state}{': ' + g['reason'] if g['reason'] else ''}")
    if state in MEANING:
        print(f"  ({MEANING[state].format(updated=clock(g['updated']))})")
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
