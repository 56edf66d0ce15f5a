"""The PDDL reader's errors in dura's words: ``file:line:col: what is wrong``.

unified-planning's reader (:mod:`.domain` calls it, the one reader of PDDL) says
``Not able to handle: (grund ?b) found at line: 20, col 31`` for a misspelt predicate,
and reports a missing ``)`` where its grammar gives up, often lines later (``Expected
':effect'``). This module words such an error as one line at the place the user must
look - ``unknown predicate 'grund' (did you mean 'ground'?)``, ``'(and' is not closed
before ':effect' (a ')' is missing)`` - and keeps the source line with a caret under the
place for a terminal (:attr:`~knowledge.errors.DuraError.excerpt`).

It does not read PDDL: it looks at the text's parentheses and at the names the
``:types``, ``:predicates``, ``:functions``, ``:constants`` and ``:objects`` sections
declare, only to word an error the reader has already found.
"""

from __future__ import annotations

import re
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass, field
from functools import partial
from itertools import islice

from knowledge.errors import did_you_mean

_WORD = re.compile(r";[^\n]*|[()]|[^\s();]+")
_NOT_HANDLED = re.compile(r"Not able to handle: \((\S+?)[\s)].*?line: (\d+), col:? (\d+)", re.S)
_ARITY = re.compile(
    r"fluent: (\S+) has arity (\d+) but (\d+) parameters.*?line: (\d+), col:? (\d+)", re.S
)
_UNDEFINED_TYPE = re.compile(
    r"Undefined parameter's type: (\S+?)\.?\s.*?line: (\d+), col:? (\d+)", re.S
)
_UNDEFINED_NAME = re.compile(r"Undefined name found: (\S+?)\.?\s.*?line: (\d+), col:? (\d+)", re.S)
_INVALID = re.compile(r"Found invalid expression: (\S+?)\.? From line: (\d+), col:? (\d+)")
_EXPECTED = re.compile(r"^(Expected .*?)(?:,\s*found .*)?\s*\(at char \d+\)", re.S)


def _words(text: str) -> frozenset[str]:
    return frozenset(text.split())


_PDDL3 = _words(
    "preference always sometime within at-most-once sometime-after sometime-before "
    "always-within hold-during hold-after"
)
# the heads of lists that are not atoms (their elements may be lists)
_LOGIC = _PDDL3 | _words(
    "define domain problem and or not imply forall exists when over either = < > <= >= "
    "+ - * / increase decrease assign scale-up scale-down minimize maximize"
)
_ACTION_KEYWORDS = _words(":parameters :duration :condition :precondition :effect")
_SECTIONS = _words(
    ":requirements :types :constants :predicates :functions :action :durative-action "
    ":domain :objects :init :goal :metric"
)
_KEYWORDS = sorted(_ACTION_KEYWORDS | _SECTIONS)
_UNREAD = "unified-planning's reader does not read"


@dataclass
class _List:
    """A parenthesised list of the text: where it opens, its head and its elements."""

    start: int
    parent: _List | None
    items: list[_List | tuple[str, int]] = field(default_factory=list)
    end: int | None = None  # offset of its ')'

    @property
    def head(self) -> str:
        first = self.items[0] if self.items else None
        return first[0].lower() if isinstance(first, tuple) else ""

    def words(self) -> list[str]:
        return [i[0] for i in self.items if isinstance(i, tuple)]


@dataclass(frozen=True)
class Explained:
    """An error worded for the user: the message and where it points (1-based)."""

    message: str
    line: int | None
    column: int | None = None


def _tokens(text: str, start: int = 0) -> Iterator[tuple[str, int]]:
    """The parentheses and words of ``text`` from offset ``start``, with their offsets."""
    for m in _WORD.finditer(text, start):
        if not m.group(0).startswith(";"):
            yield m.group(0), m.start()


def _first(text: str, start: int, count: int) -> list[tuple[str, int]]:
    return list(islice(_tokens(text, start), count))


def position(text: str, offset: int) -> tuple[int, int]:
    """The line and column (both from 1) of an offset in a text."""
    line = text.count("\n", 0, offset) + 1
    return line, offset - (text.rfind("\n", 0, offset) + 1) + 1


def _offset(text: str, line: int, column: int) -> int:
    lines = text.split("\n")
    return sum(len(x) + 1 for x in lines[: line - 1]) + column - 1


def excerpt(text: str, line: int | None, column: int | None) -> str:
    """The source line and a caret under ``column`` (empty without a line)."""
    lines = text.splitlines()
    if line is None or not 0 < line <= len(lines):
        return ""
    source = lines[line - 1].rstrip()
    gutter = f"{line:>5} | "
    if column is None:
        return gutter + source
    under = "".join(c if c == "\t" else " " for c in source[: column - 1])
    return f"{gutter}{source}\n{' ' * (len(gutter) - 2)}| {under}^"


@dataclass(frozen=True)
class Declared:
    """The names a PDDL text declares, by section (lower case, as the reader sees them)."""

    types: tuple[str, ...] = ()
    objects: tuple[str, ...] = ()  # constants and objects
    signatures: dict[str, str] = field(default_factory=dict)  # predicate/function -> params

    def __add__(self, other: Declared) -> Declared:
        return Declared(
            self.types + other.types,
            self.objects + other.objects,
            {**self.signatures, **other.signatures},
        )


def _tree(text: str) -> tuple[list[_List], list[tuple[str, _List | None, int]]]:
    """The top-level lists of the text, and each problem of its parentheses as it
    appears: (what, the list still open, offset)."""
    top: list[_List] = []
    found: list[tuple[str, _List | None, int]] = []
    current: _List | None = None
    for word, at in _tokens(text):
        if word == "(":
            opened = _List(at, current)
            (current.items if current is not None else top).append(opened)
            current = opened
        elif word == ")":
            if current is None:
                found.append(("unexpected", None, at))
            else:
                current.end = at
                current = current.parent
        elif current is not None:
            current.items.append((word, at))
    while current is not None:
        found.append(("open", current, len(text)))
        current = current.parent
    return top, found


def _walk(lists: Sequence[_List | tuple[str, int]]) -> Iterator[_List]:
    for item in lists:
        if isinstance(item, _List):
            yield item
            yield from _walk(item.items)


def _sections(top: list[_List]) -> Iterator[_List]:
    for root in top:
        if root.head == "define":
            yield from (i for i in root.items if isinstance(i, _List))


def declared(text: str) -> Declared:
    """The types, objects and signatures a domain or problem text declares."""
    top, _ = _tree(text)
    types: list[str] = []
    objects: list[str] = []
    signatures: dict[str, str] = {}
    for section in _sections(top):
        words = section.words()[1:]
        if section.head == ":types":
            types += [w.lower() for w in words if w != "-"]
        elif section.head in (":constants", ":objects"):
            objects += [
                w.lower()
                for i, w in enumerate(words)
                if w != "-" and (i == 0 or words[i - 1] != "-")
            ]
        elif section.head in (":predicates", ":functions"):
            for atom in (i for i in section.items if isinstance(i, _List)):
                name, *params = atom.words()
                signatures[name.lower()] = " ".join(params)
    return Declared(tuple(types), tuple(objects), signatures)


_DOMAIN_NAME = re.compile(r"\(\s*:?domain\s+([^\s()]+)", re.IGNORECASE)


def domain_named(text: str) -> tuple[str, int] | None:
    """The domain a domain text defines, or a problem text is written for (lower case),
    and its offset; cheap enough for every problem read."""
    found = _DOMAIN_NAME.search(uncommented(text))
    return (found.group(1).lower(), found.start()) if found else None


def _unclosed(text: str, limit: int) -> Explained | None:
    """A ``(`` left open or a ``)`` too many, found from the structure before offset
    ``limit`` (where the reader gave up): the first place where an atom holds a list, a
    section or an action's keyword stands inside another list, or the text ends open."""
    top, problems = _tree(text)
    found: list[tuple[int, Callable[[], Explained]]] = []  # where it shows, and the words
    for item in _walk(top):
        if item.start > limit:
            break
        nested = [i for i in item.items[1:] if isinstance(i, _List)]
        if nested and _is_atom(item):
            found.append((nested[0].start, partial(_open, text, item, nested[0].start)))
        for child in item.items:
            if isinstance(child, _List) and child.head.startswith(":"):
                if item.head != "define" and child.head not in _ACTION_KEYWORDS:
                    found.append((child.start, partial(_open, text, _outermost(item), child.start)))
            elif isinstance(child, tuple) and child[0].lower() in _ACTION_KEYWORDS:
                if item.head == "define":
                    found.append((child[1], partial(_outside, text, *child)))
                elif item.head not in (":action", ":durative-action"):
                    found.append((child[1], partial(_open, text, _below_action(item), child[1])))
    for kind, still_open, at in problems:
        if kind == "unexpected":
            line, column = position(text, at)
            found.append(
                (at, partial(Explained, "unexpected ')': nothing is open here", line, column))
            )
        elif still_open is not None:
            found.append((at, partial(_open, text, _outermost(still_open), at)))
    return min(found, key=lambda f: f[0])[1]() if found else None


def _outside(text: str, keyword: str, at: int) -> Explained:
    line, column = position(text, at)
    message = f"'{keyword}' is outside any action: a ')' before it closes the action too early"
    return Explained(message, line, column)


def _is_atom(item: _List) -> bool:
    """Whether a list is an atom (a predicate or function with its arguments)."""
    words = item.words()
    timed = item.head == "at" and len(words) > 1 and not words[1].startswith("?")
    return (
        bool(item.head)
        and item.head not in _LOGIC
        and not timed
        and not item.head.startswith((":", "?"))
    )


def _outermost(item: _List) -> _List:
    """The outermost list below ``define`` that holds ``item``."""
    while item.parent is not None and item.parent.head != "define":
        item = item.parent
    return item


def _below_action(item: _List) -> _List:
    """The list right inside the action that holds ``item``."""
    while item.parent is not None and item.parent.head not in (":action", ":durative-action"):
        item = item.parent
    return item


def _open(text: str, item: _List, before: int) -> Explained:
    """``item`` is still open at offset ``before``: point at its last element that spans
    lines, if it has one (an atom whose ')' is on a later line lost its own), else at it."""
    where = "the end of the file"
    if before < len(text):
        words = [w for w, _ in _first(text, before, 2)]
        what = f"({words[1]}" if words[0] == "(" and len(words) > 1 else words[0]
        where = f"'{what}' at line {position(text, before)[0]}"
    spans = [
        c
        for c in item.items
        if isinstance(c, _List)
        and _is_atom(c)
        and c.end is not None
        and c.end < before
        and position(text, c.start)[0] != position(text, c.end)[0]
    ]
    line, column = position(text, item.start)
    if spans and item.head in (":predicates", ":functions", ":init", ":objects", ":types"):
        line, column = position(text, spans[-1].start)
        return Explained(
            f"a ')' is missing here: '({item.head}' is still open at {where}", line, column
        )
    return Explained(
        f"'({item.head}' is not closed before {where} (a ')' is missing)", line, column
    )


def explain(error: BaseException, text: str, names: Declared) -> Explained:
    """Word an error of the PDDL reader on ``text``, with ``names`` for did-you-means."""
    message = str(getattr(error, "msg", "") or error)
    found = _NOT_HANDLED.search(message)
    if found:
        name, line, column = found.group(1).lower(), int(found.group(2)), int(found.group(3))
        if name in _PDDL3:
            return Explained(f"{_UNREAD} PDDL3 constraints: '({name} ...)'", line, column)
        if name in names.signatures or name in _LOGIC:
            return Explained(f"cannot read '({name} ...)' here", line, column)
        known = sorted(names.signatures)
        return Explained(f"unknown predicate '{name}'{did_you_mean(name, known)}", line, column + 1)
    found = _ARITY.search(message)
    if found:
        name, wanted, given = found.group(1), int(found.group(2)), int(found.group(3))
        params = names.signatures.get(name.lower(), "")
        takes = f"'{name}' takes {wanted} argument{'' if wanted == 1 else 's'}"
        message = f"{takes}{f' ({params})' if params else ''}, not {given}"
        return Explained(message, int(found.group(4)), int(found.group(5)))
    found = _UNDEFINED_TYPE.search(message)
    if found:
        kind, line = found.group(1), int(found.group(2))
        column = _word_column(text, line, int(found.group(3)), kind)
        hint = did_you_mean(kind, ["object", *names.types])
        return Explained(f"unknown type '{kind}'{hint}", line, column)
    found = _UNDEFINED_NAME.search(message)
    if found:
        name, line, column = found.group(1), int(found.group(2)), int(found.group(3))
        return _undefined(text, name, line, column, names)
    found = _INVALID.search(message)
    if found:
        name, line, column = found.group(1), int(found.group(2)), int(found.group(3))
        if name.lower() == "total-time":
            message = f"{_UNREAD} '(total-time)' inside an expression"
            return Explained(f"{message} (only ':metric minimize (total-time)')", line, column)
        hint = did_you_mean(name, names.objects)
        return Explained(f"unknown object '{name}'{hint}", line, column)
    if isinstance(error, KeyError) and error.args:  # the reader's lookup of an unknown type
        return _unknown_key(text, str(error.args[0]), names)
    return _syntax(error, text, message)


def uncommented(text: str) -> str:
    """The text with its comments blanked out (offsets stay)."""
    return re.sub(r";[^\n]*", lambda m: " " * len(m.group(0)), text)


def _word_column(text: str, line: int, column: int, word: str) -> int:
    """The column of ``word`` at or after ``column`` on ``line`` (else ``column``)."""
    source = text.splitlines()[line - 1] if 0 < line <= text.count("\n") + 1 else ""
    at = source.lower().find(word.lower(), column - 1)
    return at + 1 if at >= 0 else column


def _undefined(text: str, name: str, line: int, column: int, names: Declared) -> Explained:
    offset = _offset(text, line, column)
    variable = text[offset : offset + 1] == "?"
    if variable and name.lower() == "duration":
        return Explained(f"{_UNREAD} '?duration' outside the :duration constraint", line, column)
    if variable:
        top, _ = _tree(text)
        action = next(
            (
                a
                for a in _walk(top)
                if a.head in (":action", ":durative-action")
                and a.start < offset <= (a.end or len(text))
            ),
            None,
        )
        variables = [
            w for i in _walk(action.items if action else []) for w in i.words() if w.startswith("?")
        ]
        known = sorted({v.lower() for v in variables} - {f"?{name.lower()}"})
        return Explained(
            f"unknown parameter '?{name}'{did_you_mean('?' + name, known)}", line, column
        )
    return Explained(f"unknown name '{name}'{did_you_mean(name, names.objects)}", line, column)


def _unknown_key(text: str, name: str, names: Declared) -> Explained:
    typed = re.compile(rf"(?<=-)\s*({re.escape(name)})(?![\w-])", re.IGNORECASE)
    found = typed.search(uncommented(text))
    line, column = position(text, found.start(1)) if found else (None, None)
    if name.lower() == "object":
        message = f"{_UNREAD} objects declared '- object': give them a type of the domain"
        return Explained(message, line, column)
    return Explained(
        f"unknown type '{name}'{did_you_mean(name, ['object', *names.types])}", line, column
    )


def _syntax(error: BaseException, text: str, message: str) -> Explained:
    """A syntax error of the reader's grammar (pyparsing: ``loc`` is the offset)."""
    at = getattr(error, "loc", None)
    if not isinstance(at, int):
        line = getattr(error, "lineno", None)
        return Explained(
            " ".join(message.split()) or type(error).__name__,
            line if isinstance(line, int) else None,
        )
    either = re.search(r"\(\s*either\b", uncommented(text), re.IGNORECASE)
    if either is not None:  # the reader reads no `either` at all
        line, column = position(text, either.start())
        message = f"{_UNREAD} 'either' types: declare a common supertype and use it instead"
        return Explained(message, line, column)
    rest = _first(text, at, 2)
    if len(rest) > 1 and rest[0][0] == "(" and rest[1][0].startswith(":"):
        section = rest[1][0].lower()
        line, column = position(text, at)
        if section == ":constraints":
            return Explained(f"{_UNREAD} PDDL3 constraints: '(:constraints ...)'", line, column)
        if section not in _SECTIONS:
            hint = did_you_mean(section, sorted(_SECTIONS))
            return Explained(f"unknown section '({section}'{hint}", line, column)
    unclosed = _unclosed(text, at)
    if unclosed is not None:
        return unclosed
    line, column = position(text, at)
    word = rest[0][0] if rest else ""
    if word.startswith(":") and word.lower() not in _KEYWORDS:
        return Explained(
            f"unknown keyword '{word}'{did_you_mean(word.lower(), _KEYWORDS)}", line, column
        )
    expected = _EXPECTED.search(message)
    what = expected.group(1) if expected else " ".join(message.split())
    for kind, other in (("domain", "problem"), ("problem", "domain")):
        if what == f"Expected '{kind}'" and word.lower() == other:
            return Explained(f"this file is a PDDL {other}, not a {kind}", line, column)
    found = f", not '{word}'" if word else ", not the end of the file"
    return Explained(f"{what[0].lower()}{what[1:]}{found}", line, column)
