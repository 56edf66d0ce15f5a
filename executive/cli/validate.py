"""``dura validate ROBOT.yaml``: check a robot description, its PDDL domain and its observers;
or a fleet description against its domain and its robots (``dura validate fleet.yaml``)."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Any

from executive.bus.wording import plural
from executive.cli import exits_at_once
from executive.cli.output import add_json_flag, print_json, shown
from executive.cli.progress import LiveLine
from executive.fast_start import use_reader_environment
from executive.planning.integrity import read_rules as read_integrity_rules
from executive.planning.problem import read_world
from knowledge.description import RobotDescription
from knowledge.domain import DomainInfo
from knowledge.finding import Finding, Report
from knowledge.validation import validate
from monitoring.observer_config import check_observer_file, check_observers
from monitoring.repair.rule import read_rules as read_repair_rules


def register(sub: Any) -> None:
    p = sub.add_parser(
        "validate",
        help="check a robot description and its PDDL domain",
        description="Check a robot description, its PDDL domain and problem, the "
        "task-action mapping and the observer configurations; or a standalone observers "
        "file (tug form: a list of observers, or 'setup: [...]'); or a fleet description "
        "(fleet.yaml) against its domain and each robot's description. Exit 0 if valid "
        "(warnings allowed), 1 if not, 2 on usage errors.",
    )
    p.add_argument("robot", metavar="ROBOT.yaml", type=Path, help="the robot description")
    exits_at_once(p)
    add_json_flag(p)
    p.set_defaults(run=run)


def _order(f: Finding) -> tuple[str, int, int]:
    return (f.path, f.line or 0, 0 if f.is_error else 1)


def _line(f: Finding) -> str:
    """The finding's one line, and below it the source line with a caret (if it has one)."""
    line = str(Finding(shown(f.path), f.line, f.message, f.severity, f.column))
    return f"{line}\n{f.excerpt}" if f.excerpt else line


def check_rule_files(robot: RobotDescription, domain: DomainInfo) -> list[Finding]:
    """The findings of the robot's integrity rules and repair rules files."""
    objects = read_world(robot.domain, robot.problem)[0].objects if robot.problem else {}
    findings: list[Finding] = []
    for path in robot.integrity:
        report = Report(str(path))
        read_integrity_rules(path, robot, domain, objects, report)
        findings += report.findings
    for path in robot.rules:
        report = Report(str(path))
        read_repair_rules(path, report)
        findings += report.findings
    return findings


def run(args: argparse.Namespace) -> int:
    use_reader_environment()
    from executive.fleet.description import is_fleet_file

    if is_fleet_file(args.robot):
        return _fleet(args)
    observers = check_observer_file(args.robot)
    if observers is not None:
        specs, findings = observers
        summary = f"{plural(len(specs), 'observer')} ({', '.join(s.type for s in specs) or 'none'})"
        return _report(args, findings, True, summary)
    with LiveLine(shown=not args.json) as line:
        line.doing(f"checking {shown(args.robot)} and its PDDL domain")
        result = validate(args.robot)
        robot = result.robot
        findings = list(result.findings)
        if robot is not None:
            line.doing("checking the observers")
            findings += check_observers(robot)
            if result.domain is not None and not any(f.is_error for f in findings):
                line.doing("checking the rule files")
                findings += check_rule_files(robot, result.domain)
            findings = sorted(findings, key=_order)
    summary = ""
    if robot is not None:
        summary = (
            f"robot '{robot.name}', "
            f"{plural(len(robot.functionalities), 'functionality', 'functionalities')}, "
            f"{plural(len(robot.behaviors), 'behavior')}, {plural(len(robot.tasks), 'task')}, "
            f"domain '{result.domain.name if result.domain else '?'}'"
        )
    return _report(args, findings, robot is not None, summary)


def _fleet(args: argparse.Namespace) -> int:
    from executive.fleet.validation import check_fleet

    with LiveLine(shown=not args.json) as line:
        line.doing(f"checking {shown(args.robot)}, its domain and its robots")
        check = check_fleet(args.robot)
    summary = ""
    if check.fleet is not None:
        summary = (
            f"fleet '{check.fleet.name}', {plural(len(check.fleet.robots), 'robot')} "
            f"({', '.join(check.fleet.robots)}), "
            f"{plural(len(check.actors), 'action')} carried out by robots, "
            f"domain '{check.domain.name if check.domain else '?'}'"
        )
    return _report(args, sorted(check.findings, key=_order), check.fleet is not None, summary)


def _report(args: argparse.Namespace, findings: list[Finding], usable: bool, summary: str) -> int:
    errors = [f for f in findings if f.is_error]
    warnings = [f for f in findings if not f.is_error]
    valid = usable and not errors
    if args.json:
        print_json(
            {
                "file": str(args.robot),
                "valid": valid,
                "errors": len(errors),
                "warnings": len(warnings),
                "findings": [{**f.as_json(), "file": shown(f.path)} for f in findings],
            }
        )
        return 0 if valid else 1
    for f in findings:
        print(_line(f), file=sys.stderr)
    if not valid:
        return 1
    print(
        f"{shown(args.robot)}: valid: {summary}"
        + (f", {plural(len(warnings), 'warning')}" if warnings else "")
    )
    return 0
