"""The ``dura`` command line: one module per command group, registered here.

- a module per command of :data:`COMMANDS`, named as it (``register`` adds its parser,
  which sets ``run``); :mod:`.demo_ros2`, :mod:`.demo_fleet` and :mod:`.demo_timeline`
  belong to ``demo``;
- :mod:`.client` — how a command finds the running executive and asks it;
- :mod:`.arguments` — argument types: a bad value is a usage error saying what is
  allowed;
- :mod:`.output` — tables for people, JSON for scripts; :mod:`.progress` — one live line
  of what a long command does; :mod:`.stopping` — waiting for Ctrl-C or SIGTERM.

Its start-up tricks (standard modules imported at first use, garbage collection paused
while the command loads, a quick exit, a unified-planning environment that reads PDDL and
never plans) are in :mod:`executive.fast_start`.

It may import every other part of dura; it talks to a running robot over the bus.
"""

from __future__ import annotations

import argparse
import contextlib
import importlib
import os
import signal
import sys
import threading
from collections.abc import Sequence
from typing import Any

from executive import fast_start
from knowledge.errors import DuraError

# Each command, in the order ``dura --help`` lists them; ``executive/cli/<command>.py``
# registers it with ``register(subparsers)`` (its parsers set ``run(args) -> int``). Only the
# module of the command being run is imported, so that a quick command (status, goal
# list) starts in tens of milliseconds, not in the time it takes to import the planner,
# the solvers and the web stack that other commands need.
COMMANDS = (
    "demo",
    "new",
    "validate",
    "run",
    "fleet",
    "host",
    "goal",
    "plan",
    "domain",
    "state",
    "object",
    "events",
    "status",
    "task",
    "schedule",
    "component",
    "param",
    "observe",
    "observer",
    "dashboard",
    "graph",
    "diagnose",
    "record",
    "replay",
    "rules",
    "kb",
    "lsp",
    "version",
)


def _columns() -> int:
    """The terminal's width as ``shutil.get_terminal_size`` finds it (``COLUMNS``, else
    the terminal of stdout, else 80)."""
    try:
        columns = int(os.environ.get("COLUMNS", "0"))
    except ValueError:
        columns = 0
    if columns <= 0:
        try:
            columns = os.get_terminal_size(sys.__stdout__.fileno()).columns  # type: ignore[union-attr]
        except (AttributeError, ValueError, OSError):
            columns = 0
    return columns if columns > 0 else 80


class _Formatter(argparse.HelpFormatter):
    """argparse's help formatter, but without importing ``shutil`` for the width: 1.7 ms
    of every command's start (argparse makes a formatter for each argument); see
    :mod:`executive.fast_start`."""

    def __init__(
        self,
        prog: str,
        indent_increment: int = 2,
        max_help_position: int = 24,
        width: int | None = None,
    ) -> None:
        width = _columns() - 2 if width is None else width
        super().__init__(prog, indent_increment, max_help_position, width)


class _Parser(argparse.ArgumentParser):
    """argparse with one-line usage errors and exit code 2."""

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        kwargs.setdefault("formatter_class", _Formatter)
        super().__init__(*args, **kwargs)

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
    named = _command(argv)
    for module in [named] if named in COMMANDS else COMMANDS:
        importlib.import_module(f"executive.cli.{module}").register(sub)
    return parser


def _configure_logging(verbose: int) -> None:
    """Log to stderr: warnings by default, -v info, -vv debug."""
    import logging  # here: a quick command never loads logging (see execute)

    level = {0: logging.WARNING, 1: logging.INFO}.get(verbose, logging.DEBUG)
    logging.basicConfig(level=level, format="%(asctime)s %(name)s %(levelname)s: %(message)s")


def _command(argv: Sequence[str]) -> str | None:
    """The command ``argv`` names (its first word that is not an option), if any."""
    return next((word for word in argv if not word.startswith("-")), None)


def parse(argv: Sequence[str] | None = None) -> argparse.Namespace:
    """The arguments of one ``dura`` command (its module imported)."""
    argv = list(sys.argv[1:] if argv is None else argv)
    return build_parser(argv).parse_args(argv)


def main(argv: Sequence[str] | None = None) -> int:
    """Run one ``dura`` command; returns the exit code."""
    return execute(parse(argv))


def execute(args: argparse.Namespace) -> int:
    """Run a parsed command; returns the exit code."""
    if args.verbose or "logging" in sys.modules:
        # A quick command (status, goal list) never loads logging; should its bus warn
        # (a malformed message), Python prints the warning as it is, and nothing less.
        _configure_logging(args.verbose)
    try:
        return int(args.run(args))
    except DuraError as e:
        print(f"dura: {e}", file=sys.stderr)
        if e.excerpt and not getattr(args, "json", False):  # the one line first, then where
            print(e.excerpt, file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        return 130
    except BrokenPipeError:
        return 0


def entry() -> None:
    """The console script (and ``python -m executive.cli``): a command started as fast
    as :mod:`executive.fast_start` makes it."""
    if _command(sys.argv[1:]) == "run":  # a long run: glibc's thread caches off
        from executive.runtime.native_heap import restart_without_thread_caches

        restart_without_thread_caches()
    fast_start.defer_modules()  # the modules that the imports name but no quick command uses
    try:
        with fast_start.collection_paused():  # the command's imports
            args = parse()
    except KeyboardInterrupt:  # Ctrl-C while the command loads: no traceback
        sys.exit(130)
    if getattr(args, "exits_at_once", False):  # nothing of its own to clean up after Ctrl-C
        signal.signal(signal.SIGINT, _interrupted)
    code = execute(args)
    if getattr(args, "exits_at_once", False):
        fast_start.exit_at_once(code)
    sys.exit(code)


INTERRUPT_GRACE = 5.0  # seconds a command has to end after Ctrl-C


def _interrupted(signum: int, frame: Any) -> None:
    """Ctrl-C: interrupt the command as Python does, and make sure it ends. A command
    interrupted inside Zenoh (opening a session, or closing one while messages arrive)
    could otherwise wait forever at its exit; after ``INTERRUPT_GRACE`` seconds it ends
    with 130 whatever it waits for. Only for the commands that keep nothing open (see
    :func:`exits_at_once`): the others stop what they started, however long it takes."""
    with contextlib.suppress(OSError, ValueError):
        sys.stdout.flush()
    ender = threading.Timer(INTERRUPT_GRACE, os._exit, (130,))
    ender.daemon = True
    ender.start()
    raise KeyboardInterrupt


def exits_at_once(parser: Any) -> None:
    """Mark a command (and its subcommands) that keeps nothing open when it returns: no
    file being written, no process, no thread of its own (the commands that ask the
    executive and print, and those that only read files). It ends as
    :func:`executive.fast_start.exit_at_once` says."""
    parser.set_defaults(exits_at_once=True)
