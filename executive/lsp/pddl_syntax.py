"""PDDL as tokens and nested lists, each with its place in the text.

unified-planning's reader (:mod:`knowledge.domain`) is the one judge of what a PDDL file
means; it gives lines only. This reader gives the editor the rest: where each word
starts and ends, which list it belongs to, and the comments between them. It accepts
anything: an unclosed list ends at the end of the text, a stray ``)`` is skipped.
"""

from __future__ import annotations

import bisect
from dataclasses import dataclass, field


@dataclass(frozen=True)
class Token:
    """A word, a parenthesis or a comment, at ``start`` (inclusive) to ``end`` of the text."""

    kind: str  # "(", ")", "word" or "comment"
    text: str
    start: int
    end: int


@dataclass
class Form:
    """A parenthesised list: its items (words and lists), where it opens and closes."""

    start: int
    end: int  # after its ``)``; the end of the text if it is never closed
    items: list[Token | Form] = field(default_factory=list)
    closed: bool = False

    @property
    def head(self) -> str:
        """Its first word, lower-case (``:action``, ``and``, a predicate), or ``""``."""
        first = self.items[0] if self.items else None
        return first.text.lower() if isinstance(first, Token) else ""

    def words(self) -> list[Token]:
        return [i for i in self.items if isinstance(i, Token)]

    def forms(self) -> list[Form]:
        return [i for i in self.items if isinstance(i, Form)]

    def section(self, keyword: str) -> Form | None:
        """The first list in it that starts with ``keyword`` (``:predicates``)."""
        return next((f for f in self.forms() if f.head == keyword), None)

    def after(self, keyword: str) -> Token | Form | None:
        """What follows a keyword among its items (``:parameters`` -> its list)."""
        for i, item in enumerate(self.items[:-1]):
            if isinstance(item, Token) and item.text.lower() == keyword:
                return self.items[i + 1]
        return None


_DELIMITERS = frozenset("();")


def tokenize(text: str) -> list[Token]:
    """Split PDDL into tokens; comments run from ``;`` to the end of the line."""
    tokens: list[Token] = []
    i, n = 0, len(text)
    while i < n:
        c = text[i]
        if c.isspace():
            i += 1
        elif c in "()":
            tokens.append(Token(c, c, i, i + 1))
            i += 1
        elif c == ";":
            end = text.find("\n", i)
            end = n if end < 0 else end
            tokens.append(Token("comment", text[i:end].rstrip(), i, end))
            i = end
        else:
            j = i
            while j < n and not text[j].isspace() and text[j] not in _DELIMITERS:
                j += 1
            tokens.append(Token("word", text[i:j], i, j))
            i = j
    return tokens


def parse(text: str) -> Form:
    """The text as one root list of its top-level lists (comments left out)."""
    root = Form(0, len(text), closed=True)
    stack = [root]
    for token in tokenize(text):
        if token.kind == "(":
            form = Form(token.start, len(text))
            stack[-1].items.append(form)
            stack.append(form)
        elif token.kind == ")":
            if len(stack) > 1:
                form = stack.pop()
                form.end, form.closed = token.end, True
        elif token.kind == "word":
            stack[-1].items.append(token)
    return root


class Lines:
    """Offsets of a text to (line, column) and back, both counted from 0 as the protocol
    does; a column counts the code units of the encoding the client and the server agreed
    on (UTF-16 by default: an emoji is two)."""

    def __init__(self, text: str, encoding: str = "utf-16") -> None:
        self.text = text
        self.encoding = encoding
        self.starts = [0] + [i + 1 for i, c in enumerate(text) if c == "\n"]

    def position(self, offset: int) -> tuple[int, int]:
        line = bisect.bisect_right(self.starts, offset) - 1
        return line, self.units(line, offset - self.starts[line])

    def offset(self, line: int, column: int) -> int:
        if line >= len(self.starts):
            return len(self.text)
        start = self.starts[max(line, 0)]
        text = self.line_text(max(line, 0))
        if self.encoding == "utf-32" or text.isascii():
            return start + min(max(column, 0), len(text))
        units = 0
        for i, c in enumerate(text):
            if units >= column:
                return start + i
            units += _units(c, self.encoding)
        return start + len(text)

    def units(self, line: int, column: int) -> int:
        """The code units of the first ``column`` characters of a line."""
        text = self.line_text(line)[: max(column, 0)]
        if self.encoding == "utf-32" or text.isascii():
            return max(column, 0)
        return sum(_units(c, self.encoding) for c in text) + max(column - len(text), 0)

    def line_text(self, line: int) -> str:
        if not 0 <= line < len(self.starts):
            return ""
        end = self.starts[line + 1] - 1 if line + 1 < len(self.starts) else len(self.text)
        return self.text[self.starts[line] : end]


def _units(c: str, encoding: str) -> int:
    if encoding == "utf-8":
        return len(c.encode("utf-8", "surrogatepass"))
    return 2 if ord(c) > 0xFFFF else 1  # utf-16: a surrogate pair beyond the BMP


def typed_list(items: list[Token | Form]) -> list[tuple[Token, Token | None]]:
    """The names of a typed list (``?a ?b - place ?c``) with the token of each one's type."""
    pairs: list[tuple[Token, Token | None]] = []
    pending: list[Token] = []
    words = [i for i in items if isinstance(i, Token)]
    i = 0
    while i < len(words):
        word = words[i]
        if word.text == "-" and i + 1 < len(words):
            pairs += [(p, words[i + 1]) for p in pending]
            pending = []
            i += 2
            continue
        if word.text != "-":
            pending.append(word)
        i += 1
    pairs += [(p, None) for p in pending]
    return pairs
