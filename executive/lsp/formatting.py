"""PDDL in its canonical layout: the user's lines, each indented by two spaces per open
list, one space between words, none inside parentheses, comments kept where they are
(a comment after code keeps its gap),
at most one blank line in a row. Formatting formatted text changes nothing."""

from __future__ import annotations

from executive.lsp.pddl_syntax import Token, tokenize

INDENT = "  "


def format_pddl(text: str) -> str:
    """The text laid out canonically (the same text if it is so already)."""
    by_line: dict[int, list[Token]] = {}
    line = 0
    last = 0
    for token in tokenize(text):
        line += text.count("\n", last, token.start)
        last = token.start
        by_line.setdefault(line, []).append(token)
    total = text.count("\n") + 1
    out: list[str] = []
    depth = 0
    for number in range(total):
        tokens = by_line.get(number, [])
        if not tokens:
            if out and out[-1] != "":
                out.append("")
            continue
        leading = 0
        while leading < len(tokens) and tokens[leading].kind == ")":
            leading += 1
        indent = max(depth - leading, 0)
        out.append(INDENT * indent + _join(text, tokens))
        for token in tokens:
            depth += {"(": 1, ")": -1}.get(token.kind, 0)
        depth = max(depth, 0)
    while out and out[-1] == "":
        out.pop()
    return "\n".join(out) + "\n" if out else ""


def _join(text: str, tokens: list[Token]) -> str:
    """A line's tokens; a comment after code keeps its gap (comments aligned stay so)."""
    written = ""
    previous: Token | None = None
    for token in tokens:
        if previous is not None and token.kind == "comment":
            written += " " * max(token.start - previous.end, 1)
        elif previous is not None and previous.kind != "(" and token.kind != ")":
            written += " "
        written += token.text
        previous = token
    return written
