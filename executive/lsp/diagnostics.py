"""A finding as the editor shows it: at the exact place of the name it is about.

A finding has a line, and PDDL findings a column too (``file:line:col: reason``): the
place is the word that starts at that column; without a column, the one unified-planning's
message gives (``from line: 5, col 15 to line: 5, col 19``), else that of the last name it
quotes which the line holds (``requires unknown capability 'scna'`` -> ``scna``), else
the line's text. A did-you-mean travels with the diagnostic, for the code action that applies it.
"""

from __future__ import annotations

import re

from lsprotocol import types

from executive.lsp.pddl_syntax import Lines
from knowledge.finding import Finding

SOURCE = "dura"
_QUOTED = re.compile(r"'([^'\s]+)'")
_SPAN = re.compile(r"line:? (\d+), col:? (\d+) to line:? (\d+), col:? (\d+)", re.IGNORECASE)
_WORD = re.compile(r"\(?[^\s()]+")
_DID_YOU_MEAN = re.compile(r" \(did you mean '([^']+)'\?\)")


def diagnostic(finding: Finding, lines: Lines) -> types.Diagnostic:
    """The finding as a diagnostic in the text ``lines`` (in their encoding's units)."""
    line = max((finding.line or 1) - 1, 0)
    text = lines.line_text(line)
    message = finding.message
    suggestion = _DID_YOU_MEAN.search(message)
    plain = _DID_YOU_MEAN.sub("", message)
    quoted = [m.group(1) for m in _QUOTED.finditer(plain)]
    start, end = _at_column(text, finding.column - 1) if finding.column else _place(text, quoted)
    span = _SPAN.search(message)  # unified-planning's own place: lines and columns from 1
    if span is not None and int(span.group(1)) - 1 == line:
        first, column, last, end_column = (int(g) - 1 for g in span.groups())
    else:
        first, column, last, end_column = line, start, line, end
    where = types.Range(  # the columns found are characters; the client counts its units
        types.Position(first, lines.units(first, column)),
        types.Position(last, lines.units(last, end_column)),
    )
    fix = None
    if suggestion is not None:
        written = lines.line_text(first)[column:end_column] if first == last else ""
        fix = {"replacement": suggestion.group(1), "name": written}
    return types.Diagnostic(
        range=where,
        message=message,
        severity=types.DiagnosticSeverity.Error
        if finding.is_error
        else types.DiagnosticSeverity.Warning,
        source=SOURCE,
        data=fix,
    )


def fix_range(shown: types.Diagnostic, lines: Lines) -> types.Range:
    """Where a did-you-mean's name is in the text now: the diagnostic's range as the
    client sent it back may be off (Neovim 0.7 sends byte columns for UTF-16 ones), so
    the name is looked for on its line, the nearest to that range."""
    data = shown.data if isinstance(shown.data, dict) else {}
    name = data.get("name")
    line = shown.range.start.line
    if not isinstance(name, str) or not name or shown.range.end.line != line:
        return shown.range
    found = [
        (lines.units(line, m.start()), lines.units(line, m.end()))
        for m in re.finditer(_whole(name), lines.line_text(line), re.IGNORECASE)
    ]
    if not found:
        return shown.range
    start, end = min(found, key=lambda f: abs(f[0] - shown.range.start.character))
    return types.Range(types.Position(line, start), types.Position(line, end))


def _whole(name: str) -> str:
    """A pattern of ``name`` written as a whole word."""
    return rf"(?<![\w?:-]){re.escape(name)}(?![\w-])"


def _at_column(text: str, start: int) -> tuple[int, int]:
    """The columns of the word (or the parenthesised head, ``(define``) that starts at
    ``start``; one character where none does."""
    word = _WORD.match(text, start)
    return start, word.end() if word is not None and word.end() > start else start + 1


def _place(text: str, names: list[str]) -> tuple[int, int]:
    """The columns of the last of ``names`` written in ``text`` as a whole word, else of
    the text without its indentation and comment."""
    code = re.split(r";|(?:^|\s)#", text, maxsplit=1)[0]  # no PDDL or YAML comment
    for name in reversed(names):
        found = re.search(_whole(name), code, re.IGNORECASE)
        if found:
            return found.start(), found.end()
    stripped = code.rstrip()
    start = len(stripped) - len(stripped.lstrip())
    return start, max(len(stripped), start)
