"""``dura version``: dura's version and those of the engines it runs on."""

from __future__ import annotations

import argparse
import platform
from importlib import metadata
from typing import Any

from executive import __version__
from executive.cli.output import add_json_flag, print_json, table

DEPENDENCIES = (
    "unified-planning",
    "up-kairos",
    "up-aries",
    "up-fast-downward",
    "clingo",
    "eclipse-zenoh",
    "networkx",
    "psutil",
    "pyyaml",
)


def register(sub: Any) -> None:
    p = sub.add_parser(
        "version",
        help="print the versions of dura and its engines",
        description="Print the versions of dura, Python, and the libraries and planning "
        "engines it runs on (which planners are installed).",
    )
    add_json_flag(p)
    p.set_defaults(run=run)


def versions() -> dict[str, str]:
    out = {"dura": __version__, "python": platform.python_version()}
    for name in DEPENDENCIES:
        try:
            out[name] = metadata.version(name)
        except metadata.PackageNotFoundError:
            out[name] = "not installed"
    return out


def run(args: argparse.Namespace) -> int:
    found = versions()
    if args.json:
        print_json(found)
    else:
        table(["package", "version"], sorted(found.items(), key=lambda kv: kv[0] != "dura"))
    return 0
