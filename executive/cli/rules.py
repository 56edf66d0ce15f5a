"""``dura rules check RULES.yaml``: validate a repair rules file."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Any

from executive.bus.wording import plural
from executive.cli.output import add_json_flag, print_json, shown
from knowledge.errors import AspError
from knowledge.finding import Finding, Report, finding_of
from monitoring.repair.engine import RuleEngine
from monitoring.repair.rule import read_rules


def register(sub: Any) -> None:
    p = sub.add_parser("rules", help="repair rules", description="Work with repair rule files.")
    rules = p.add_subparsers(dest="rules_command", metavar="COMMAND")
    rules.required = True
    check = rules.add_parser(
        "check",
        help="validate a rules file",
        description="Read a repair rules file (thesis schema) and the ASP files it names; "
        "report every problem as file:line: message. Exit 0 if valid, 1 if not.",
    )
    check.add_argument("rules", metavar="RULES.yaml", type=Path, help="the rules file")
    add_json_flag(check)
    check.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    report = Report(shown(args.rules))
    rule_set = read_rules(args.rules, report)
    findings: list[Finding] = list(report.findings)
    if not report.errors:
        try:
            RuleEngine([rule_set])
        except AspError as e:
            findings.append(finding_of(e, shown(args.rules)))
    errors = [f for f in findings if f.is_error]
    if args.json:
        print_json(
            {
                "file": str(args.rules),
                "valid": not errors,
                "rules": [
                    {"name": r.name, "action": r.action.describe(), "line": r.line}
                    for r in rule_set.rules
                ],
                "findings": [f.as_json() for f in findings],
            }
        )
        return 1 if errors else 0
    for finding in findings:
        print(finding, file=sys.stderr)
    if errors:
        return 1
    print(f"{shown(args.rules)}: valid: {plural(len(rule_set.rules), 'rule')}")
    for rule in rule_set.rules:
        print(f"  {rule.name}: {rule.action.describe()}")
    return 0
