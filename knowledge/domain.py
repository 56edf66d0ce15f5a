"""Read temporal PDDL with unified-planning and describe the domain's signatures.

The UP reader is the one parser of PDDL in dura; this module turns its errors into
:class:`DomainError` messages with ``file:line`` and extracts what the robot
description is checked against (actions, their parameters, predicates, types).
"""

from __future__ import annotations

import re
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

from knowledge.errors import DomainError, located

if TYPE_CHECKING:
    from unified_planning.model import Problem

_EMPTY_FUNCTIONS = re.compile(r"\(\s*:functions\s*\)", re.IGNORECASE)
_UP_LINE = re.compile(r"line:? (\d+)")
_ACTION_HEAD = re.compile(r"\(\s*:(durative-action|action)\s+([^\s()]+)", re.IGNORECASE)


@dataclass(frozen=True)
class ActionInfo:
    """A PDDL action's name, typed parameters and where it is written."""

    name: str
    parameters: tuple[tuple[str, str], ...]
    durative: bool
    line: int | None = None

    @property
    def parameter_names(self) -> tuple[str, ...]:
        return tuple(p for p, _ in self.parameters)


@dataclass(frozen=True)
class DomainInfo:
    """The signatures of a domain: what tasks and goals may name."""

    name: str
    path: Path
    actions: Mapping[str, ActionInfo] = field(default_factory=dict)
    predicates: Mapping[str, tuple[str, ...]] = field(default_factory=dict)
    functions: Mapping[str, tuple[str, ...]] = field(default_factory=dict)
    types: tuple[str, ...] = ()
    constants: Mapping[str, str] = field(default_factory=dict)
    supertypes: Mapping[str, str | None] = field(default_factory=dict)  # type -> parent


def _read(path: Path) -> str:
    try:
        return path.read_text(encoding="utf-8")
    except OSError as e:
        raise DomainError(located(path, None, f"cannot read: {e.strerror or e}")) from e
    except UnicodeDecodeError as e:
        raise DomainError(located(path, None, "is not UTF-8 text")) from e


def _prepare(text: str) -> str:
    """Work around reader limits without moving any line: drop empty `(:functions)`."""
    return _EMPTY_FUNCTIONS.sub(lambda m: " " * len(m.group(0)), text)


def _error_line(error: BaseException) -> int | None:
    lineno = getattr(error, "lineno", None)
    if isinstance(lineno, int) and lineno > 0:
        return lineno
    found = _UP_LINE.search(str(error))
    return int(found.group(1)) if found else None


def _error_text(error: BaseException) -> str:
    text = str(getattr(error, "msg", "") or error) or type(error).__name__
    text = re.sub(r"\s*\(at char \d+\),?\s*\(line:\d+, col:\d+\)", "", text)
    return " ".join(text.split())


def parse(domain: Path) -> Problem:
    """Parse a domain into a UP problem with no objects, initial state or goals.

    Raises:
        DomainError: naming the file and line of the first syntax or semantic error.
    """
    from unified_planning.io import PDDLReader

    try:
        return PDDLReader().parse_problem_string(_prepare(_read(domain)), None)
    except Exception as e:  # the reader raises pyparsing, SyntaxError and UP exceptions
        raise DomainError(located(domain, _error_line(e), f"PDDL: {_error_text(e)}")) from e


def parse_problem(
    domain: Path, problem_text: str, source: str = "problem", *, domain_checked: bool = False
) -> Problem:
    """Parse a domain with a problem given as text (the problem's errors name ``source``;
    unless ``domain_checked``, the domain is parsed alone first, so that its own errors
    name the domain file)."""
    from unified_planning.io import PDDLReader

    if not domain_checked:
        parse(domain)
    try:
        return PDDLReader().parse_problem_string(_prepare(_read(domain)), problem_text)
    except Exception as e:
        raise DomainError(located(source, _error_line(e), f"PDDL: {_error_text(e)}")) from e


def read_domain(path: Path) -> DomainInfo:
    """Parse a domain file and describe its signatures.

    Raises:
        DomainError: the file cannot be read or is not a valid PDDL domain.
    """
    return describe(parse(path), path)


def describe(problem: Problem, path: Path) -> DomainInfo:
    """The signatures of a parsed domain (``path``: its file, for the actions' lines)."""
    text = _read(path)
    lines = {
        m.group(2).lower(): text.count("\n", 0, m.start()) + 1 for m in _ACTION_HEAD.finditer(text)
    }
    actions: dict[str, ActionInfo] = {}
    for action in problem.actions:
        params = tuple((p.name, str(p.type)) for p in action.parameters)
        durative = type(action).__name__ == "DurativeAction"
        actions[action.name] = ActionInfo(
            action.name, params, durative, lines.get(action.name.lower())
        )
    predicates: dict[str, tuple[str, ...]] = {}
    functions: dict[str, tuple[str, ...]] = {}
    for fluent in problem.fluents:
        signature = tuple(str(p.type) for p in fluent.signature)
        (predicates if fluent.type.is_bool_type() else functions)[fluent.name] = signature
    constants = {o.name: str(o.type) for o in problem.all_objects}
    types = tuple(str(t) for t in problem.user_types)
    parents = {str(t): str(t.father) if t.father else None for t in problem.user_types}
    return DomainInfo(problem.name, path, actions, predicates, functions, types, constants, parents)
