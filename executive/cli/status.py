"""``dura status``: what a running robot does, at a glance."""

from __future__ import annotations

import argparse
import sys
from typing import Any

from executive.bus.api import planning as api
from executive.bus.event_text import diagnosis
from executive.cli import exits_at_once
from executive.cli.client import add_client_options, ask
from executive.cli.goal import GOAL_HEADERS, goal_rows
from executive.cli.output import add_json_flag, print_json, section, table


def register(sub: Any) -> None:
    status = sub.add_parser(
        "status",
        help="goals, plan, tasks, components and diagnoses at a glance",
        description="Print a running robot's goals, its plan with the state of each step, "
        "the tasks and the components they use, faults and the newest diagnosis.",
    )
    status.set_defaults(run=run_status)
    exits_at_once(status)
    add_client_options(status)
    add_json_flag(status)


def run_status(args: argparse.Namespace) -> int:
    status = ask(args, api.STATUS)
    if args.json:
        print_json(status.to_payload())
        return 0
    print_status(status)
    return 0


def print_status(status: api.StatusReply, out: Any = None) -> None:
    out = out or sys.stdout
    whose = "fleet" if status.robots is not None else "robot"
    total = sum((status.goal_counts or {}).values())
    shown = len(status.goals)
    left = f" (the open ones and the newest: {shown} of {total}; all: dura goal list)"
    section(f"{whose} {status.robot}: goals{left if total > shown else ''}", out, first=True)
    table(GOAL_HEADERS, goal_rows(status.goals), out)
    plan = status.plan
    if plan is not None:
        section(f"plan {plan.id} ({plan.state.value}, by {plan.engine})", out)
        states = status.execution.states_of(plan)
        table(
            ["#", "start", "duration", "step", "state"],
            [
                [
                    s.index,
                    f"{s.start:.3f}",
                    "-" if s.duration is None else f"{s.duration:g}",
                    f"{s.action}({', '.join(s.args)})",
                    states.get(s.index, "-"),
                ]
                for s in plan.steps
            ],
            out,
        )
    if isinstance(status.tasks, list):
        section("tasks", out)
        table(
            ["id", "task", "state", "uses"],
            [[t.id, t.name, t.state, ", ".join(sorted(t.functionalities))] for t in status.tasks],
            out,
        )
    if isinstance(status.robots, list):
        section("robots", out)
        table(
            ["robot", "available", "reason"],
            [[r.robot, "yes" if r.available else "no", r.reason] for r in status.robots],
            out,
        )
    if isinstance(status.components, list):
        section("components", out)
        table(
            ["name", "kind", "state", "pid"],
            [[c.component, c.kind, c.state.value, c.pid] for c in status.components],
            out,
        )
    if status.faults:
        section("faults", out)
        table(
            ["component", "faults", "permanent", "reason"],
            [[f.name, f.fault_count, f.permanent_fault, f.reason] for f in status.faults],
            out,
        )
    if status.diagnosis is not None:
        section(f"diagnosis: {diagnosis(status.diagnosis)}", out)
