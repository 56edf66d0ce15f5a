"""A problem found in a user's input, located at a file and line."""

from __future__ import annotations

import enum
import re
from dataclasses import dataclass

from knowledge.errors import located


class Severity(enum.Enum):
    ERROR = "error"
    WARNING = "warning"


@dataclass(frozen=True)
class Finding:
    """One problem in one file: ``path:line: message`` (``path:line:col: message`` with
    a column; ``excerpt``: the source line with a caret under the place, for a terminal)."""

    path: str
    line: int | None
    message: str
    severity: Severity = Severity.ERROR
    column: int | None = None
    excerpt: str = ""

    @property
    def is_error(self) -> bool:
        return self.severity is Severity.ERROR

    def __str__(self) -> str:
        prefix = "warning: " if self.severity is Severity.WARNING else ""
        return located(self.path, self.line, prefix + self.message, self.column)

    def as_json(self) -> dict[str, object]:
        return {
            "file": self.path,
            "line": self.line,
            "column": self.column,
            "severity": self.severity.value,
            "message": self.message,
        }


class Report:
    """Collects the findings about one file, in the order they are found."""

    def __init__(self, path: str) -> None:
        self.path = path
        self.findings: list[Finding] = []

    def error(self, line: int | None, message: str) -> None:
        self.findings.append(Finding(self.path, line, message))

    def warning(self, line: int | None, message: str) -> None:
        self.findings.append(Finding(self.path, line, message, Severity.WARNING))

    @property
    def errors(self) -> list[Finding]:
        return [f for f in self.findings if f.is_error]


_LOCATED = re.compile(r"^((?:(?!: ).)+?):(\d+)(?::(\d+))?: (.+)$", re.S)  # no ': ' in the path


def finding_of(error: Exception, fallback: str) -> Finding:
    """A finding from an error whose message reads ``file:line: message`` or
    ``file:line:col: message`` (PDDL, ASP), or one about ``fallback`` with the whole
    message."""
    text = str(error)
    excerpt = getattr(error, "excerpt", "")
    found = _LOCATED.match(text)
    if found:
        path, line, column, rest = found.groups()
        return Finding(
            path, int(line), rest, column=int(column) if column else None, excerpt=excerpt
        )
    return Finding(fallback, None, text, excerpt=excerpt)
