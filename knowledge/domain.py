"""Read temporal PDDL with unified-planning and describe the domain's signatures.

The UP reader is the one parser of PDDL in dura; this module turns its errors into
:class:`DomainError` messages with ``file:line`` and extracts what the robot
description is checked against (actions, their parameters, predicates, types).

Names of different kinds may be equal, as PDDL allows and the planning executives users
come from accept: a ROSPlan problem declares ``driver - driver``, an object named like
its type. unified-planning refuses that by default; dura turns its environment's
``error_used_name`` switch off, which still refuses a name declared twice as the same
kind (two objects ``depot``), reported at the second declaration's line.
"""

from __future__ import annotations

import re
import warnings
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

from knowledge.errors import DomainError, located
from knowledge.pddl_errors import (
    Declared,
    Explained,
    declared,
    domain_named,
    excerpt,
    explain,
    position,
    uncommented,
)
from knowledge.sources import read_text, remembered

if TYPE_CHECKING:
    from unified_planning.model import Problem

_EMPTY_FUNCTIONS = re.compile(r"\(\s*:functions\s*\)", re.IGNORECASE)
_USED_NAME = re.compile(r"Name (?:of \w+ )?(\S+) already defined")
_ACTION_HEAD = re.compile(r"\(\s*:(durative-action|action)\s+([^\s()]+)", re.IGNORECASE)
_COMMENT = re.compile(r";[^\n]*")
_DURATION = re.compile(r":duration\s*\(", re.IGNORECASE)


@dataclass(frozen=True)
class ActionInfo:
    """A PDDL action's name, typed parameters and where it is written."""

    name: str
    parameters: tuple[tuple[str, str], ...]
    durative: bool
    line: int | None = None
    duration: str | None = None  # a durative action's constraint as written: (= ?duration 2)

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
    # each predicate's and function's parameter names as the domain writes them (?from ?to)
    parameter_names: Mapping[str, tuple[str, ...]] = field(default_factory=dict)

    def is_a(self, kind: str, wanted: str) -> bool:
        """Whether type ``kind`` is ``wanted`` or one of its subtypes (at any depth)."""
        return is_a(kind, wanted, self.supertypes)

    def objects_of(self, wanted: str, objects: Mapping[str, str]) -> list[str]:
        """The constants and ``objects`` (name → type) of type ``wanted`` or a subtype."""
        return sorted(n for n, t in {**self.constants, **objects}.items() if self.is_a(t, wanted))

    def signature(self, name: str) -> str:
        """A predicate's or function's parameters as the domain writes them:
        ``?obj - locatable ?loc - place`` (``none`` without parameters)."""
        kinds = self.predicates.get(name, self.functions.get(name, ()))
        names = self.parameter_names.get(name) or tuple(f"?{i + 1}" for i in range(len(kinds)))
        return " ".join(f"{n} - {k}" for n, k in zip(names, kinds, strict=False)) or "none"


def is_a(kind: str, wanted: str, parents: Mapping[str, str | None]) -> bool:
    """Whether type ``kind`` is ``wanted`` or one of its subtypes, given each type's
    parent; every type is an ``object``."""
    seen: set[str] = set()
    current: str | None = kind
    while current is not None and current not in seen:
        if current == wanted:
            return True
        seen.add(current)
        current = parents.get(current)
    return wanted == "object"


def type_name(kind: Any) -> str:
    """A PDDL type's name. unified-planning prints a subtype as ``child - parent``; that
    text is not a name (``problem.user_type`` does not know it)."""
    name = getattr(kind, "name", None)
    return name if isinstance(name, str) else str(kind)


def _read(path: Path) -> str:
    try:
        return read_text(path)
    except OSError as e:
        raise DomainError(located(path, None, f"cannot read: {e.strerror or e}")) from e
    except UnicodeDecodeError as e:
        raise DomainError(located(path, None, "is not UTF-8 text")) from e


def _prepare(text: str) -> str:
    """Work around reader limits without moving any line: drop empty `(:functions)`."""
    return _EMPTY_FUNCTIONS.sub(lambda m: " " * len(m.group(0)), text)


def _error(source: object, error: BaseException, text: str, names: Declared) -> DomainError:
    """The reader's error on ``text`` (the file ``source``) as ``file:line:col: reason``,
    with the line and a caret under the place as its excerpt."""
    used = _USED_NAME.search(str(error))
    if used:
        line, column = _second_declaration(text, used.group(1))
        where = Explained(f"name '{used.group(1)}' is declared twice", line, column)
    else:
        where = explain(error, text, names)
    message = located(source, where.line, where.message, where.column)
    return DomainError(message, excerpt=excerpt(text, where.line, where.column))


def _second_declaration(text: str, name: str) -> tuple[int | None, int | None]:
    """The line and column where a name declared twice is written the second time."""
    word = re.compile(rf"(?<![\w?-]){re.escape(name)}(?![\w-])", re.IGNORECASE)
    found = list(word.finditer(uncommented(text)))
    return position(text, found[1].start()) if len(found) > 1 else (None, None)


def _reader() -> Any:
    """UP's PDDL reader, in an environment where names of different kinds may be equal."""
    # here, not at the top: the executive's process imports this module (DomainInfo) and
    # leaves unified-planning to its planner worker, and a process that reads PDDL sets
    # unified-planning up before it loads (executive.fast_start)
    from unified_planning.environment import get_environment
    from unified_planning.io import PDDLReader

    environment = get_environment()
    environment.error_used_name = False  # still refuses a name declared twice as one kind
    warnings.filterwarnings("ignore", message=r"Name .* already defined")
    return PDDLReader(environment)


def _parsed(domain_text: str, problem_text: str | None) -> Problem:
    """UP's reading of a domain (and a problem), remembered where the language server
    asks for it (:func:`knowledge.sources.remembered`), with the reader itself: building
    its grammar costs a third of reading the use case's domain. (A reader keeps nothing
    of one text that it uses for the next: its ``total-cost`` fluent is set anew by every
    domain that declares one and read only then.)"""
    return remembered(
        ("pddl", domain_text, problem_text),
        lambda: remembered(("pddl reader",), _reader, _itself).parse_problem_string(
            domain_text, problem_text
        ),
        lambda problem: problem.clone(),
    )


def _itself(reader: Any) -> Any:
    return reader


def parse(domain: Path) -> Problem:
    """Parse a domain into a UP problem with no objects, initial state or goals.

    Raises:
        DomainError: naming the file and line of the first syntax or semantic error.
    """
    text = _read(domain)
    try:
        return _parsed(_prepare(text), None)
    except Exception as e:  # the reader raises pyparsing, SyntaxError and UP exceptions
        raise _error(domain, e, text, declared(text)) from e


def parse_problem(
    domain: Path, problem_text: str, source: str = "problem", *, domain_checked: bool = False
) -> Problem:
    """Parse a domain with a problem given as text (the problem's errors name ``source``;
    unless ``domain_checked``, the domain is parsed alone first, so that its own errors
    name the domain file)."""
    if not domain_checked:
        parse(domain)
    domain_text = _read(domain)
    try:
        problem = _parsed(_prepare(domain_text), problem_text)
    except Exception as e:
        names = declared(domain_text) + declared(problem_text)
        raise _error(source, e, problem_text, names) from e
    _check_domain_name(domain_named(domain_text), domain_named(problem_text), problem_text, source)
    return problem


def _check_domain_name(
    defined: tuple[str, int] | None, named: tuple[str, int] | None, text: str, source: object
) -> None:
    """Refuse a problem written for another domain (the reader does not look)."""
    if defined is None or named is None or defined[0] == named[0]:
        return
    line, column = position(text, named[1])
    message = f"the problem is for domain '{named[0]}', not '{defined[0]}'"
    raise DomainError(located(source, line, message, column), excerpt=excerpt(text, line, column))


def _balanced(text: str, start: int) -> str:
    """The parenthesised expression that opens at ``text[start]`` (to the end if open)."""
    depth = 0
    for i in range(start, len(text)):
        depth += {"(": 1, ")": -1}.get(text[i], 0)
        if depth == 0:
            return text[start : i + 1]
    return text[start:]


def _durations(text: str) -> dict[str, str]:
    """Each action's ``:duration`` constraint as written, on one line, by lower-case name."""
    code = _COMMENT.sub(lambda m: " " * len(m.group(0)), text)  # offsets stay
    found: dict[str, str] = {}
    for head in _ACTION_HEAD.finditer(code):
        body = _balanced(code, head.start())
        duration = _DURATION.search(body)
        if duration is not None:
            constraint = _balanced(body, duration.end() - 1)
            found[head.group(2).lower()] = " ".join(constraint.replace("( ", "(").split())
    return found


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
    durations = _durations(text)
    actions: dict[str, ActionInfo] = {}
    for action in problem.actions:
        params = tuple((p.name, type_name(p.type)) for p in action.parameters)
        durative = type(action).__name__ == "DurativeAction"
        key = action.name.lower()
        actions[action.name] = ActionInfo(
            action.name, params, durative, lines.get(key), durations.get(key) if durative else None
        )
    predicates: dict[str, tuple[str, ...]] = {}
    functions: dict[str, tuple[str, ...]] = {}
    names: dict[str, tuple[str, ...]] = {}
    for fluent in problem.fluents:
        signature = tuple(type_name(p.type) for p in fluent.signature)
        (predicates if fluent.type.is_bool_type() else functions)[fluent.name] = signature
        names[fluent.name] = tuple(f"?{p.name}" for p in fluent.signature)
    constants = {o.name: type_name(o.type) for o in problem.all_objects}
    types = tuple(type_name(t) for t in problem.user_types)
    parents = {type_name(t): type_name(t.father) if t.father else None for t in problem.user_types}
    return DomainInfo(
        problem.name, path, actions, predicates, functions, types, constants, parents, names
    )
