"""``dura kb show|check|repair``: the knowledge base, readably or as JSON; whether it is
sound; a repair that keeps what can be read."""

from __future__ import annotations

import argparse
import sys
import time
from collections import Counter
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from executive.bus.event_text import describe
from executive.bus.wording import plural, seconds
from executive.cli.arguments import count
from executive.cli.output import add_json_flag, print_json, section, shown, table
from knowledge.errors import DuraError
from knowledge.health import check, repair
from knowledge.knowledge_base import KnowledgeBase
from knowledge.records import PlanStep
from knowledge.robot import read_robot


def register(sub: Any) -> None:
    p = sub.add_parser("kb", help="inspect the knowledge base")
    kb_sub = p.add_subparsers(dest="kb_command", metavar="KB_COMMAND")
    kb_sub.required = True
    show = kb_sub.add_parser(
        "show",
        help="print goals, plans, tasks, facts, components and recent events",
        description="Print a robot's knowledge base. Name the robot description (its KB "
        "is ./.dura/<robot>.db unless it says otherwise) or the database file.",
    )
    show.add_argument(
        "--events", type=count, default=20, metavar="N", help="how many recent events (20)"
    )
    show.set_defaults(run=run_show)
    check = kb_sub.add_parser(
        "check",
        help="check that the knowledge base is sound (every page readable, every table there)",
        description="Read every page of a knowledge base and say what is wrong with it, "
        "without changing it. Exit 0 if it is sound, 1 if not.",
    )
    check.set_defaults(run=run_check)
    repair = kb_sub.add_parser(
        "repair",
        help="move a damaged knowledge base aside and keep every row that can be read",
        description="Move the damaged file aside (FILE.damaged-<time>, never deleted) and "
        "write a sound knowledge base with every row that can still be read. Stop the "
        "executive first.",
    )
    repair.set_defaults(run=run_repair)
    for cmd in (show, check, repair):
        where = cmd.add_mutually_exclusive_group(required=True)
        where.add_argument(
            "robot", metavar="ROBOT.yaml", type=Path, nargs="?", help="the robot description"
        )
        where.add_argument("--db", type=Path, help="the knowledge base file")
        add_json_flag(cmd)


def database_path(args: argparse.Namespace) -> Path:
    """The KB file named by ``--db`` or by a robot description."""
    if args.db is not None:
        return Path(args.db)
    robot, findings = read_robot(args.robot)
    errors = [f for f in findings if f.is_error]
    if robot is None:
        raise DuraError(str(errors[0]) if errors else f"{args.robot}: unusable")
    return robot.kb_path()


def _clock(stamp: float) -> str:
    return time.strftime("%H:%M:%S", time.localtime(stamp))


def run_show(args: argparse.Namespace) -> int:
    with KnowledgeBase(database_path(args), readonly=True) as kb:
        if args.json:
            print_json(kb.snapshot(events=args.events))
            return 0
        print(f"knowledge base {shown(str(kb.path))} (schema {kb.schema_version})")
        section("goals")
        table(
            ["id", "state", "priority", "deadline", "source", "expression", "reason"],
            [
                [g.id, g.state.value, g.priority, None if g.deadline is None else seconds(g.deadline),
                 g.source, g.expression, g.reason]
                for g in kb.goals()
            ],
        )  # fmt: skip
        section("plans")
        table(
            ["id", "state", "engine", "goals", "steps"],
            [[p.id, p.state.value, p.engine, p.goal_ids, _steps(p.steps)] for p in kb.plans()],
        )
        section("tasks")
        table(
            ["id", "state", "action", "behavior", "args", "reason"],
            [[t.id, t.state.value, t.action, t.behavior, t.args, t.reason] for t in kb.tasks()],
        )
        section("objects")
        table(["name", "type"], sorted(kb.objects().items()))
        section("facts")
        for fact in kb.facts():
            print(f"  {fact.text}")
        section("components")
        table(
            ["name", "rating", "faults", "permanent", "reason"],
            [
                [c.name, c.rating, c.fault_count, c.permanent_fault, c.reason]
                for c in kb.components()
            ],
        )
        section(f"last {plural(args.events, 'event')}")
        table(
            ["id", "time", "kind", "event"],
            [[e.id, _clock(e.stamp), e.kind, describe(e)] for e in kb.events(limit=args.events)],
        )
    return 0


def run_check(args: argparse.Namespace) -> int:
    health = check(database_path(args))
    if args.json:
        print_json(
            {"file": str(health.path), "sound": health.sound, "problems": list(health.problems),
             "rows": health.rows}
        )  # fmt: skip
        return 0 if health.sound else 1
    if not health.sound:
        for problem in health.problems:
            print(f"{shown(health.path)}: {problem}", file=sys.stderr)
        return 1
    rows = ", ".join(f"{n} {t}" for t, n in health.rows.items() if n)
    print(f"{shown(health.path)}: sound ({rows or 'empty'})")
    return 0


def run_repair(args: argparse.Namespace) -> int:
    path = database_path(args)
    health = check(path)
    if health.sound:
        raise DuraError(f"{shown(path)}: sound, nothing to repair")
    done = repair(path)
    if args.json:
        print_json(
            {"file": str(done.path), "damaged_file": str(done.kept_aside), "kept": done.kept,
             "lost": done.lost}
        )  # fmt: skip
        return 0
    kept = sum(done.kept.values())
    lost = sum(done.lost.values())
    print(f"{shown(done.path)}: repaired: kept {plural(kept, 'row')}, could not read {lost}")
    print(f"the damaged file is kept as {shown(done.kept_aside)}")
    return 0


def _steps(steps: Sequence[PlanStep]) -> str:
    """``3: 1 ended, 1 cancelled, 1 pending``: how many steps, and what happened to them."""
    counts = Counter(s.state for s in steps)
    return (
        f"{len(steps)}: " + ", ".join(f"{n} {state}" for state, n in counts.items())
        if steps
        else "0"
    )
