"""``dura validate ROBOT.yaml``: check a robot description and its PDDL domain."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Any

from executive.cli.output import add_json_flag, print_json, shown
from knowledge.finding import Finding
from knowledge.validation import validate


def register(sub: Any) -> None:
    p = sub.add_parser(
        "validate",
        help="check a robot description and its PDDL domain",
        description="Check a robot description, its PDDL domain and problem, and the "
        "task-action mapping. Exit 0 if valid (warnings allowed), 1 if not, 2 on usage errors.",
    )
    p.add_argument("robot", metavar="ROBOT.yaml", type=Path, help="the robot description")
    add_json_flag(p)
    p.set_defaults(run=run)


def _line(f: Finding) -> str:
    return str(Finding(shown(f.path), f.line, f.message, f.severity))


def run(args: argparse.Namespace) -> int:
    result = validate(args.robot)
    if args.json:
        print_json(
            {
                "file": str(args.robot),
                "valid": result.ok,
                "errors": len(result.errors),
                "warnings": len(result.warnings),
                "findings": [{**f.as_json(), "file": shown(f.path)} for f in result.findings],
            }
        )
        return 0 if result.ok else 1
    for f in result.findings:
        print(_line(f), file=sys.stderr)
    robot = result.robot
    if robot is None or not result.ok:
        return 1
    print(
        f"{shown(args.robot)}: valid: robot '{robot.name}', {len(robot.functionalities)} "
        f"functionalities, {len(robot.behaviors)} behaviors, {len(robot.tasks)} tasks, "
        f"domain '{result.domain.name if result.domain else '?'}'"
        + (f", {len(result.warnings)} warnings" if result.warnings else "")
    )
    return 0
