"""The ``dura`` command line: one module per command group, registered here."""

from __future__ import annotations

import argparse
import importlib
import logging
import sys
from collections.abc import Sequence

from knowledge.errors import DuraError

# Each command's module, in the order ``dura --help`` lists them. A module registers its
# commands with ``register(subparsers)`` (its parsers set ``run(args) -> int``). Only the
# module of the command being run is imported, so that a quick command (status, goal
# list) starts in tens of milliseconds, not in the time it takes to import the planner,
# the solvers and the web stack that other commands need.
COMMANDS: dict[str, str] = {
    "demo": "demo",
    "validate": "validate",
    "run": "run",
    "goal": "goal",
    "plan": "plan",
    "state": "world",
    "object": "world",
    "events": "status",
    "status": "status",
    "task": "task",
    "schedule": "task",
    "component": "component",
    "observe": "observe",
    "dashboard": "dashboard",
    "graph": "graph",
    "diagnose": "diagnose",
    "record": "record",
    "replay": "replay",
    "rules": "rules",
    "kb": "kb",
    "version": "version",
}


class _Parser(argparse.ArgumentParser):
    """argparse with one-line usage errors and exit code 2."""

    def error(self, message: str) -> None:  # type: ignore[override]
        self.exit(2, f"{self.prog}: error: {message} (see '{self.prog} --help')\n")


def build_parser(argv: Sequence[str] = ()) -> argparse.ArgumentParser:
    """The parser for ``argv``: with the command it names only (all of them for help and
    for a command that does not exist, so that the error lists them)."""
    parser = _Parser(
        prog="dura",
        description="dura: a dependable robot executive (plan, execute, monitor, diagnose, repair).",
    )
    parser.add_argument(
        "-v", "--verbose", action="count", default=0, help="more log output (-vv: debug)"
    )
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", parser_class=_Parser)
    sub.required = True
    named = next((word for word in argv if not word.startswith("-")), None)
    wanted = [COMMANDS[named]] if named in COMMANDS else list(COMMANDS.values())
    for module in dict.fromkeys(wanted):
        importlib.import_module(f"executive.cli.{module}").register(sub)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Run one ``dura`` command; returns the exit code."""
    argv = list(sys.argv[1:] if argv is None else argv)
    args = build_parser(argv).parse_args(argv)
    level = {0: logging.WARNING, 1: logging.INFO}.get(args.verbose, logging.DEBUG)
    logging.basicConfig(level=level, format="%(asctime)s %(name)s %(levelname)s: %(message)s")
    try:
        return int(args.run(args))
    except DuraError as e:
        print(f"dura: {e}", file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        return 130
    except BrokenPipeError:
        return 0


def entry() -> None:
    """The console script."""
    sys.exit(main())
