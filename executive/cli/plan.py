"""``dura plan --offline DOMAIN PROBLEM``: plan without a robot, for domain authors."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Any

from executive.cli.output import add_json_flag, print_json, shown, table
from executive.goal import GoalSpec
from executive.partial_order import PartialOrderPlan, Step
from executive.planner import Planner, PlanningTask, PlanResult, engine_names
from executive.problem import read_world
from knowledge.description import DEFAULT_ENGINE
from knowledge.errors import DuraError

BAR = 40  # characters of the timeline


def register(sub: Any) -> None:
    p = sub.add_parser(
        "plan",
        help="plan for a PDDL problem without a robot (--offline)",
        description="Plan for the goal of a PDDL problem with one of dura's engines, validate "
        "the plan, and print it as a timeline. Exit 0 with a plan, 1 without one.",
    )
    p.add_argument(
        "--offline",
        nargs=2,
        metavar=("DOMAIN", "PROBLEM"),
        type=Path,
        required=True,
        help="the domain and problem PDDL files",
    )
    p.add_argument(
        "--engine",
        default=DEFAULT_ENGINE,
        choices=engine_names(),
        help=f"the planning engine (default {DEFAULT_ENGINE})",
    )
    p.add_argument(
        "--timeout", type=float, default=30.0, metavar="S", help="seconds to search (30)"
    )
    add_json_flag(p)
    p.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    domain, problem = args.offline
    if not args.timeout > 0:
        raise DuraError(f"--timeout must be a positive number of seconds, not {args.timeout:g}")
    world, goal = read_world(domain, problem)
    task = PlanningTask(domain.resolve(), world, (GoalSpec(0, goal),))
    with Planner(args.engine, args.timeout) as planner:
        result = planner.solve(task)
    if args.json:
        print_json(as_json(result))
        return 0 if result.ok else 1
    if not result.ok or result.plan is None:
        print(f"dura: {shown(problem)}: no plan: {result.reason}", file=sys.stderr)
        return 1
    print(
        f"{shown(problem)}: {len(result.plan.steps)} steps, makespan {result.plan.makespan:g} s, "
        f"by {result.engine} in {result.time:.2f} s, validated by {result.validator}"
    )
    print_timeline(result.plan)
    return 0


def _after(step: Step) -> str:
    return (
        " ".join(f"{p.step}{'' if p.at.value == 'end' else '(start)'}" for p in step.after) or "-"
    )


def print_timeline(plan: PartialOrderPlan) -> None:
    """The steps as a table with a bar for each, scaled to the makespan."""
    span = plan.makespan or 1.0
    rows = []
    for s in plan.steps:
        first = int(s.start / span * BAR)
        width = max(1, round((s.duration or 0.0) / span * BAR))
        bar = " " * first + "█" * min(width, BAR - first)
        dur = "-" if s.duration is None else f"{s.duration:g}"
        rows.append([s.index, f"{s.start:.3f}", dur, s.label, _after(s), f"|{bar.ljust(BAR)}|"])
    table(["#", "start", "duration", "step", "after", "timeline"], rows)


def as_json(result: PlanResult) -> dict[str, Any]:
    plan = result.plan
    return {
        "status": result.status.value,
        "engine": result.engine,
        "time": round(result.time, 4),
        "validator": result.validator,
        "reason": result.reason,
        "makespan": plan.makespan if plan is not None else None,
        "steps": [
            {
                "index": s.index,
                "action": s.action,
                "args": list(s.args),
                "start": s.start,
                "duration": s.duration,
                "after": [{"step": p.step, "at": p.at.value} for p in s.after],
            }
            for s in (plan.steps if plan is not None else ())
        ],
        "log": list(result.log),
    }
