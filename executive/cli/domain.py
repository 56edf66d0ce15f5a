"""``dura domain check DOMAIN [PROBLEM]``: diagnostics for domain authors, beyond syntax."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Any

from executive.cli.output import add_json_flag, print_json, shown


def register(sub: Any) -> None:
    p = sub.add_parser("domain", help="check a PDDL domain for what its author missed")
    dsub = p.add_subparsers(dest="domain_command", metavar="DOMAIN_COMMAND")
    dsub.required = True
    check = dsub.add_parser(
        "check",
        help="predicates nothing adds, actions never applicable, unused types and predicates",
        description="Check a PDDL domain (and a problem of it) beyond syntax and print each "
        "finding as 'file:line: warning: ...': predicates that actions or the goal need but no "
        "action adds; with a problem, actions that can never be applied from its initial "
        "state and goal atoms that can never hold (relaxed reachability); types, predicates "
        "and functions nothing uses. Exit 0 (warnings allowed), 1 if the PDDL is invalid, "
        "2 on usage errors.",
    )
    check.add_argument("domain", metavar="DOMAIN", type=Path, help="the domain PDDL file")
    check.add_argument(
        "problem", metavar="PROBLEM", type=Path, nargs="?", help="a problem PDDL file (optional)"
    )
    add_json_flag(check)
    check.set_defaults(run=run_check)


def run_check(args: argparse.Namespace) -> int:
    from executive.planning.domain_check import check_domain  # unified-planning is slow to load
    from knowledge.finding import Finding

    findings = check_domain(args.domain, args.problem)
    if args.json:
        print_json(
            {
                "domain": str(args.domain),
                "problem": None if args.problem is None else str(args.problem),
                "warnings": len(findings),
                "findings": [{**f.as_json(), "file": shown(f.path)} for f in findings],
            }
        )
        return 0
    for f in findings:
        print(Finding(shown(f.path), f.line, f.message, f.severity))
    checked = shown(args.domain) + (f" with {shown(args.problem)}" if args.problem else "")
    print(
        f"{checked}: {len(findings) or 'no'} warning{'s' * (len(findings) != 1)}", file=sys.stderr
    )
    return 0
