"""The ``dura`` command line: one module per command group, registered here."""

from __future__ import annotations

import argparse
import logging
import sys
from collections.abc import Sequence
from types import ModuleType

from executive.cli import (
    component,
    dashboard,
    demo,
    diagnose,
    goal,
    graph,
    kb,
    observe,
    param,
    plan,
    rules,
    run,
    status,
    task,
    validate,
    version,
    world,
)
from knowledge.errors import DuraError

# Each module has register(subparsers); its parsers set `run(args) -> int`.
COMMANDS: tuple[ModuleType, ...] = (
    demo,
    validate,
    run,
    goal,
    plan,
    world,
    status,
    task,
    component,
    param,
    observe,
    dashboard,
    graph,
    diagnose,
    rules,
    kb,
    version,
)


class _Parser(argparse.ArgumentParser):
    """argparse with one-line usage errors and exit code 2."""

    def error(self, message: str) -> None:  # type: ignore[override]
        self.exit(2, f"{self.prog}: error: {message} (see '{self.prog} --help')\n")


def build_parser() -> argparse.ArgumentParser:
    parser = _Parser(
        prog="dura",
        description="dura: a dependable robot executive (plan, execute, monitor, diagnose, repair).",
    )
    parser.add_argument(
        "-v", "--verbose", action="count", default=0, help="more log output (-vv: debug)"
    )
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", parser_class=_Parser)
    sub.required = True
    for module in COMMANDS:
        module.register(sub)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Run one ``dura`` command; returns the exit code."""
    args = build_parser().parse_args(argv)
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
