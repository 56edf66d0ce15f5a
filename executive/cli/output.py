"""How commands print for people (tables) and for scripts (JSON)."""

from __future__ import annotations

import json
import os
import sys
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any, TextIO

from executive.bus.wording import pairs


def add_json_flag(parser: Any) -> None:
    parser.add_argument("--json", action="store_true", help="print machine-readable JSON")


def print_json(data: Any, out: TextIO | None = None) -> None:
    json.dump(data, out or sys.stdout, indent=2, sort_keys=False, default=str)
    (out or sys.stdout).write("\n")


def shown(path: str | Path) -> str:
    """A path as the user would write it: relative to the working folder when inside it."""
    text = str(path)
    try:
        rel = os.path.relpath(text)
    except ValueError:
        return text
    return rel if not rel.startswith("..") else text


def table(headers: Sequence[str], rows: Sequence[Sequence[Any]], out: TextIO | None = None) -> None:
    """Print rows under headers in aligned columns."""
    out = out or sys.stdout
    cells = [[_cell(v) for v in row] for row in rows]
    widths = [len(h) for h in headers]
    for row in cells:
        for i, value in enumerate(row):
            widths[i] = max(widths[i], len(value))
    line = "  ".join(h.upper().ljust(w) for h, w in zip(headers, widths, strict=True))
    out.write(line.rstrip() + "\n")
    for row in cells:
        out.write("  ".join(v.ljust(w) for v, w in zip(row, widths, strict=True)).rstrip() + "\n")


BAR = 40  # characters of a timeline


def bar(start: float, duration: float | None, span: float) -> str:
    """A step's place in a timeline of ``BAR`` characters scaled to ``span`` seconds."""
    span = span or 1.0
    first = min(BAR - 1, int(start / span * BAR))
    width = max(1, round((duration or 0.0) / span * BAR))
    return "|" + (" " * first + "█" * min(width, BAR - first)).ljust(BAR) + "|"


def section(title: str, out: TextIO | None = None, *, first: bool = False) -> None:
    """A title, after a blank line unless it is the ``first`` thing printed."""
    (out or sys.stdout).write(f"{title}\n" if first else f"\n{title}\n")


def _cell(value: Any) -> str:
    if value is None:
        return "-"
    if isinstance(value, bool):
        return "yes" if value else "no"
    if isinstance(value, float):
        return f"{value:g}"
    if isinstance(value, (list, tuple)):
        return " ".join(_cell(v) for v in value) or "-"
    if isinstance(value, Mapping):
        return pairs(value) or "-"
    return str(value)
