"""Where the text of an input file comes from: the file, or an editor's unsaved buffer.

Every reader of PDDL and YAML input reads through :func:`read_text`. The language server
(``dura lsp``) checks what the user sees in the editor, not what is on disk: it runs the
checks inside :func:`unsaved`, which lends the open documents' texts to the readers of
the current thread (a context variable: other threads and tasks still read the files),
and a memo in which the PDDL reader keeps what it parsed, by text (:func:`remembered`),
so that a change to one file does not parse the others again.
"""

from __future__ import annotations

import contextlib
from collections import OrderedDict
from collections.abc import Callable, Hashable, Iterator, Mapping
from contextvars import ContextVar
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, TypeVar

T = TypeVar("T")


class Memo:
    """The last ``size`` results (or errors) of a reader, by what was read."""

    def __init__(self, size: int = 32) -> None:
        self.size = size
        self.results: OrderedDict[Hashable, tuple[bool, Any]] = OrderedDict()


@dataclass(frozen=True)
class _Reading:
    texts: Mapping[Path, str] = field(default_factory=dict)
    memo: Memo | None = None


_READING: ContextVar[_Reading] = ContextVar("reading", default=_Reading())  # noqa: B039 - frozen


def read_text(path: Path) -> str:
    """The text of ``path``: an editor's unsaved buffer of it, else the file (UTF-8).

    Raises:
        OSError, UnicodeDecodeError: as :meth:`Path.read_text`.
    """
    text = unsaved_text(path)
    return Path(path).read_text(encoding="utf-8") if text is None else text


def unsaved_text(path: Path) -> str | None:
    """An editor's unsaved buffer of ``path``, if one is lent (see :func:`unsaved`)."""
    buffers = _READING.get().texts
    return buffers.get(Path(path).resolve()) if buffers else None


def remembered(key: Hashable, read: Callable[[], T], copy: Callable[[T], T]) -> T:
    """``read()``, or, inside :func:`unsaved` with a memo, a ``copy`` of what it gave for
    the same ``key`` before (the error it raised, raised again)."""
    memo = _READING.get().memo
    if memo is None:
        return read()
    if key not in memo.results:
        try:
            memo.results[key] = (True, read())
        except Exception as e:  # the reader's error, for the next read of the same text
            memo.results[key] = (False, e)
        while len(memo.results) > memo.size:
            memo.results.popitem(last=False)
    memo.results.move_to_end(key)
    ok, value = memo.results[key]
    if not ok:
        raise value
    return copy(value)


@contextlib.contextmanager
def unsaved(texts: Mapping[Path, str], memo: Memo | None = None) -> Iterator[None]:
    """Let :func:`read_text` see ``texts`` (by resolved path) instead of the files, and
    :func:`remembered` keep results in ``memo``."""
    token = _READING.set(_Reading({Path(p).resolve(): t for p, t in texts.items()}, memo))
    try:
        yield
    finally:
        _READING.reset(token)
