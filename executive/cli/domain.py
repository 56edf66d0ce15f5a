"""``dura domain show|check``: a robot's PDDL domain and the tasks that carry out its
actions (from its running executive or, ``--offline``, its files); diagnostics for domain
authors beyond syntax."""

from __future__ import annotations

import argparse
import itertools
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from executive.bus.api import planning as api
from executive.cli import exits_at_once
from executive.cli.client import add_client_options, ask
from executive.cli.output import add_json_flag, print_json, section, shown, table
from knowledge.errors import ConfigError


def register(sub: Any) -> None:
    p = sub.add_parser(
        "domain",
        help="show a robot's PDDL domain and its tasks; check a domain for what its author missed",
    )
    exits_at_once(p)
    dsub = p.add_subparsers(dest="domain_command", metavar="DOMAIN_COMMAND")
    dsub.required = True
    show = dsub.add_parser(
        "show",
        help="types, predicates, functions, actions (parameters, duration, task)",
        description="Print the domain of the running robot: its types, predicates and "
        "functions, and each action with its parameters, its duration and the task that "
        "carries it out (behavior and goal fields), and whether it can run now (a "
        "permanently faulty component may forbid it). With --offline, read the robot "
        "description named by --robot and its domain instead of asking the executive.",
    )
    show.add_argument(
        "--offline",
        action="store_true",
        help="read the files of --robot ROBOT.yaml; ask no executive",
    )
    add_client_options(show)
    add_json_flag(show)
    show.set_defaults(run=run_show, parser=show)
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


def run_show(args: argparse.Namespace) -> int:
    if args.offline:
        if args.robot is None:
            args.parser.error("--offline reads the robot description named by --robot ROBOT.yaml")
        reply = offline(args.robot)
    else:
        reply = ask(args, api.DOMAIN_SHOW)
    if args.json:
        print_json(reply.to_payload())
        return 0
    print_domain(reply, running=not args.offline)
    return 0


def offline(description: Path) -> api.DomainReply:
    """The domain of a robot description, read from its files.

    Raises:
        ConfigError: the description or its domain is invalid (the first problem).
    """
    # unified-planning and the domain reader: only offline (every command module is
    # imported for `dura --help`)
    from executive.fast_start import use_reader_environment
    from executive.planning.domain_description import describe
    from knowledge.validation import validate

    use_reader_environment()
    result = validate(description)
    errors = [f for f in result.findings if f.is_error]
    if errors or result.robot is None or result.domain is None:
        more = f" (and {len(errors) - 1} more: run 'dura validate')" if len(errors) > 1 else ""
        excerpt = errors[0].excerpt if errors else ""
        raise ConfigError(
            f"{errors[0]}{more}" if errors else f"{description}: unusable", excerpt=excerpt
        )
    return describe(result.domain, result.robot)


def parameters(typed: Sequence[tuple[str, str]]) -> str:
    """PDDL's own way: ``?from ?to - place``."""
    groups = itertools.groupby(typed, key=lambda p: p[1])
    return " ".join(f"{' '.join(p[0] for p in group)} - {kind}" for kind, group in groups)


def _task(action: api.DomainAction) -> str:
    if action.task is None:
        return "- (no task: it completes at once)"
    fields = ", ".join(f"{k}={v}" for k, v in action.goal.items())
    return f"{action.behavior}({fields})"


def print_domain(reply: api.DomainReply, *, running: bool) -> None:
    print(f"domain {reply.name} ({shown(reply.path)})")
    section("types")
    table(["type", "parent"], [[t.name, t.parent] for t in reply.types])
    for title, signatures in (("predicates", reply.predicates), ("functions", reply.functions)):
        if signatures:
            section(title)
            table(
                [title[:-1], "parameters"],
                [[s.name, " ".join(s.parameters)] for s in signatures],
            )
    if reply.constants:
        section("constants")
        table(["constant", "type"], sorted(reply.constants.items()))
    section("actions")
    headers = ["action", "parameters", "duration", "task (behavior and goal)"]
    rows = [[a.name, parameters(a.parameters), a.duration or "-", _task(a)] for a in reply.actions]
    if running:
        headers.append("can run")
        for row, action in zip(rows, reply.actions, strict=True):
            row.append("yes" if action.blocked is None else f"no: {action.blocked}")
    table(headers, rows)


def run_check(args: argparse.Namespace) -> int:
    from executive.planning.domain_check import check_domain  # unified-planning is slow to load
    from knowledge.finding import Finding  # beside the domain check

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
