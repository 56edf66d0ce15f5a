"""The reference pages generated from dura's code, for MkDocs (a hook, see mkdocs.yml).

A page holds a marker, ``<!-- generated: NAME -->``; the hook puts in its place what
:data:`GENERATORS` makes of the code now: the robot description's schema (from the
reader's declarations, :func:`knowledge.field_plan.fields_of`), the command line (from
its argparse parsers), the bus API (from the verbs of :mod:`executive.bus.api`) and the
changelog; and it adds the pictures that live elsewhere in the repository. The tests
call the generators too (``tests/test_docs.py``).
"""

from __future__ import annotations

import argparse
import dataclasses
import enum
import importlib
import inspect
import io
import re
import tokenize
import types
import typing
from collections.abc import Callable, Iterator, Mapping
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parent.parent
MARKER = re.compile(r"<!-- generated: ([\w-]+) -->")


# --- the robot description --------------------------------------------------------------


def _sections() -> list[tuple[str, type, str]]:
    """Each part of a robot description: where it is written, its class, what it is."""
    from knowledge.description import BehaviorSpec, FunctionalitySpec, PlannerSpec, TaskSpec
    from knowledge.robot import BusSpec, RobotFile
    from knowledge.ros2_spec import Ros2Spec
    from knowledge.sensing_spec import SensingRuleSpec

    return [
        ("top level", RobotFile, "The keys of the file."),
        ("planner", PlannerSpec, "The planning engine and its time limit."),
        ("bus", BusSpec, "How the robot's processes reach each other."),
        ("functionalities: NAME", FunctionalitySpec, FunctionalitySpec.__doc__ or ""),
        ("behaviors: NAME", BehaviorSpec, BehaviorSpec.__doc__ or ""),
        ("tasks: ACTION", TaskSpec, TaskSpec.__doc__ or ""),
        ("ros2", Ros2Spec, Ros2Spec.__doc__ or ""),
        ("sensing: [RULE]", SensingRuleSpec, "A rule that turns a topic into a fact or value."),
    ]


# keys whose schema is another file's or another page's
NOTES = {
    "observers": "the observer schema: see [Watch components](../how-to/observers.md)",
    "rules": "repair rules: see [Diagnose and repair](../how-to/diagnosis-and-repair.md)",
    "integrity": "integrity rules: see [Goals and planning](../explanation/planning.md)",
}


def robot_description() -> str:
    """The schema of a robot description, one table per part."""
    from knowledge.field_plan import fields_of

    out = []
    sections = _sections()
    anchors = {cls: _anchor(title) for title, cls, _ in sections}
    for title, cls, about in sections:
        out += [f"## `{title}`", "", " ".join(about.split()), ""]
        out += ["| key | value | default | |", "| --- | --- | --- | --- |"]
        comments = _comments(cls)
        for spec in fields_of(cls):
            if spec.fill is not None:  # filled by the reader (name, lines), not written
                continue
            value = _shown_type(spec.annotation, anchors)
            default = "required" if spec.required else _shown_default(spec.default)
            note = comments.get(spec.name) or NOTES.get(spec.key, "")
            out.append(f"| `{spec.key}` | {value} | {default} | {note} |")
        out.append("")
    return "\n".join(out)


def _anchor(title: str) -> str:
    return re.sub(r"[^a-z0-9]+", "-", title.lower()).strip("-")


def _comments(cls: type) -> dict[str, str]:
    """The comment after each field of a class's source (``name: int = 0  # what``)."""
    found: dict[str, str] = {}
    try:
        source = inspect.getsource(cls)
    except (OSError, TypeError):
        return found
    field = None
    for token in tokenize.generate_tokens(io.StringIO(source).readline):
        if token.type == tokenize.NEWLINE:
            field = None
        elif token.type == tokenize.NAME and field is None and token.start[1] == 4:
            field = token.string
        elif token.type == tokenize.COMMENT and field is not None:
            text = token.string.lstrip("#").strip()
            if not text.startswith(("noqa", "type:", "fmt:")):
                found[field] = text.replace("|", "\\|")
    return found


def _shown_type(annotation: Any, anchors: Mapping[type, str]) -> str:
    from knowledge.conventions import AtLeast, AtMost, Exists, OneOf, OneOrMore
    from knowledge.field_plan import split

    base, meta = split(annotation)
    origin, args = typing.get_origin(base), typing.get_args(base)
    if origin in (types.UnionType, typing.Union):
        shown = [_shown_type(a, anchors) for a in args if a is not type(None)]
        text = " or ".join(shown) + (" or null" if type(None) in args else "")
    elif origin is tuple:
        item = _shown_type(args[0], anchors)
        text = (
            f"{item} or a list of them"
            if any(isinstance(m, OneOrMore) for m in meta)
            else (f"list of {item}")
        )
    elif origin in (Mapping, dict) or base is Mapping:
        value = _shown_type(args[1], anchors) if len(args) > 1 else "any"
        text = f"mapping of names to {value}"
    elif isinstance(base, type) and base in anchors:
        text = f"[{base.__name__}](#{anchors[base]})"
    elif isinstance(base, type) and dataclasses.is_dataclass(base):
        text = "mapping"
    elif isinstance(base, type) and issubclass(base, enum.Enum):
        text = " or ".join(f"`{m.value}`" for m in base)
    elif base is Path:
        text = "a file (relative to the description)"
    else:
        text = {str: "text", int: "integer", float: "number", bool: "true or false"}.get(
            base, "any"
        )
    for m in meta:
        if isinstance(m, AtLeast | AtMost):
            text += f", {m}"
        elif isinstance(m, OneOf):
            text = "one of " + ", ".join(f"`{c}`" for c in m.choices)
        elif isinstance(m, Exists):
            text = "an existing file (relative to the description)"
    return text


def _shown_default(default: Any) -> str:
    from knowledge.field_plan import MISSING

    if default is MISSING:
        return "-"
    value = default() if callable(default) else default
    if value in ((), {}, None, ""):
        return "-"
    if dataclasses.is_dataclass(value):
        return "see its table"
    if isinstance(value, float):
        return f"`{value:g}`"
    if isinstance(value, bool):
        return f"`{str(value).lower()}`"
    return f"`{value}`"


# --- the command line ---------------------------------------------------------------------


def command_line() -> str:
    """Every ``dura`` command with its help, as argparse has it."""
    from executive.cli import COMMANDS, build_parser

    out = []
    parser = build_parser()
    for action in parser._subparsers._group_actions if parser._subparsers else ():
        if not isinstance(action, argparse._SubParsersAction):
            continue
        for name in COMMANDS:
            out += list(_command(f"dura {name}", action.choices[name], level=2))
    return "\n".join(out)


def _command(prog: str, parser: argparse.ArgumentParser, level: int) -> Iterator[str]:
    yield f"{'#' * level} `{prog}`"
    yield ""
    parser.prog = prog
    parser.formatter_class = _wide
    yield "```text"
    yield parser.format_help().rstrip()
    yield "```"
    yield ""
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for name, sub in action.choices.items():
                yield from _command(f"{prog} {name}", sub, min(level + 1, 4))


def _wide(prog: str) -> argparse.HelpFormatter:
    return argparse.HelpFormatter(prog, width=92, max_help_position=32)


# --- the bus API ----------------------------------------------------------------------------

BUS_MODULES = ("planning", "tasks", "components", "parameters", "monitoring", "hosts")


def bus_api() -> str:
    """Each verb of the bus API: its key, request and reply, module by module."""
    from executive.bus.verb import Verb

    out = []
    for name in BUS_MODULES:
        module = importlib.import_module(f"executive.bus.api.{name}")
        out += [f"## `executive.bus.api.{name}`", ""]
        out += [" ".join((module.__doc__ or "").split()), ""]
        out += [
            "| verb | key (under `dura/ROBOT/`) | request | reply |",
            "| --- | --- | --- | --- |",
        ]
        for attribute, value in vars(module).items():
            if isinstance(value, Verb):
                out.append(
                    f"| `{attribute}` | `{value.key}` | {_fields(value.request)} | "
                    f"{_fields(value.reply)} |"
                )
        out.append("")
    return "\n".join(out)


def _fields(cls: type) -> str:
    if not dataclasses.is_dataclass(cls):
        return f"`{cls.__name__}`"
    names = ", ".join(f.name for f in dataclasses.fields(cls))
    return f"`{cls.__name__}`" + (f" ({names})" if names else "")


# --- the hook -----------------------------------------------------------------------------


def changelog() -> str:
    text = (ROOT / "CHANGELOG.md").read_text(encoding="utf-8")
    return text.split("\n", 1)[1]  # its title is the page's


GENERATORS: dict[str, Callable[[], str]] = {
    "robot-description": robot_description,
    "cli": command_line,
    "bus-api": bus_api,
    "changelog": changelog,
}


PICTURES = {"assets/dashboard.png": ROOT / "examples" / "usecase" / "dashboard.png"}
"""Pictures the pages show that live elsewhere in the repository (not copied into docs/)."""


def on_files(files: Any, config: Any, **_: Any) -> Any:
    """MkDocs: the pictures of :data:`PICTURES` among the site's files."""
    from mkdocs.structure.files import File

    for destination, source in PICTURES.items():
        files.append(File.generated(config, destination, abs_src_path=str(source)))
    return files


def on_page_markdown(markdown: str, **_: Any) -> str:
    """MkDocs: a page's markers replaced by what their generators make."""
    return MARKER.sub(lambda m: GENERATORS[m.group(1)](), markdown)
