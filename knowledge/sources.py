"""Where the text of an input file comes from: the file, or an editor's unsaved buffer.

Every reader of PDDL and YAML input reads through :func:`read_text`. The language server
(``dura lsp``) checks what the user sees in the editor, not what is on disk: it runs the
checks inside :func:`unsaved`, which lends the open documents' texts to the readers of
the current thread (a context variable: other threads and tasks still read the files).
"""

from __future__ import annotations

import contextlib
from collections.abc import Iterator, Mapping
from contextvars import ContextVar
from pathlib import Path

_UNSAVED: ContextVar[Mapping[Path, str]] = ContextVar("unsaved", default={})  # noqa: B039 - never mutated


def read_text(path: Path) -> str:
    """The text of ``path``: an editor's unsaved buffer of it, else the file (UTF-8).

    Raises:
        OSError, UnicodeDecodeError: as :meth:`Path.read_text`.
    """
    buffers = _UNSAVED.get()
    if buffers:
        text = buffers.get(Path(path).resolve())
        if text is not None:
            return text
    return Path(path).read_text(encoding="utf-8")


@contextlib.contextmanager
def unsaved(texts: Mapping[Path, str]) -> Iterator[None]:
    """Let :func:`read_text` see ``texts`` (by resolved path) instead of the files."""
    token = _UNSAVED.set({Path(p).resolve(): t for p, t in texts.items()})
    try:
        yield
    finally:
        _UNSAVED.reset(token)
