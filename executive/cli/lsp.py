"""``dura lsp``: the language server for PDDL, robot descriptions and rule files (stdio)."""

from __future__ import annotations

import argparse
import logging
from typing import Any

from executive.cli import exits_at_once


def register(sub: Any) -> None:
    p = sub.add_parser(
        "lsp",
        help="a language server for editors: PDDL, robot descriptions, rules (stdio)",
        description="Speak the Language Server Protocol on stdin and stdout, for an "
        "editor: the checks of 'dura validate' and 'dura domain check' as you type, hover, "
        "go to definition, references, completion, outline, formatting of PDDL and quick "
        "fixes, for PDDL domains and problems, robot descriptions and their rule files. "
        "Needs the 'lsp' extra: pip install 'dura[lsp]'.",
    )
    exits_at_once(p)
    p.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    try:  # here: pygls is an extra, and the other commands start without it
        from executive.lsp.server import make_server
    except ImportError as e:
        raise SystemExit(f"dura lsp: {e.name} is not installed: pip install 'dura[lsp]'") from e
    from executive import __version__
    from executive.fast_start import use_reader_environment

    use_reader_environment()
    handler = logging.StreamHandler()  # stderr: the editor's log of the server
    handler.setFormatter(_OneLine())
    for name in ("pygls", "executive.lsp"):
        logger = logging.getLogger(name)
        logger.handlers, logger.propagate = [handler], False
    make_server(__version__).start_io()
    return 0


class _OneLine(logging.Formatter):
    """A problem the server met (a malformed message from the client, say) on one line,
    with its reason and no traceback."""

    def format(self, record: logging.LogRecord) -> str:
        error = record.exc_info[1] if record.exc_info else None
        return f"dura lsp: {record.getMessage()}" + (f": {error}" if error else "")
