"""Log files of component processes, rotated by size."""

from __future__ import annotations

import os
from collections import deque
from pathlib import Path


class LogFile:
    """An append-only file ``name.log`` rotated to ``name.log.1`` ... ``name.log.N``.

    Args:
        path: the current log file; its folder is created.
        max_bytes: rotate before a write would make the file larger than this.
        backups: how many rotated files to keep.
    """

    def __init__(self, path: Path, *, max_bytes: int, backups: int) -> None:
        self.path = path
        self.max_bytes = max_bytes
        self.backups = backups
        path.parent.mkdir(parents=True, exist_ok=True)
        self._fd = self._open()
        self._size = os.fstat(self._fd).st_size

    def _open(self) -> int:
        return os.open(self.path, os.O_WRONLY | os.O_CREAT | os.O_APPEND | os.O_CLOEXEC, 0o644)

    def write(self, data: bytes) -> None:
        if self._size and self._size + len(data) > self.max_bytes:
            self._rotate()
        os.write(self._fd, data)
        self._size += len(data)

    def _rotate(self) -> None:
        os.close(self._fd)
        for i in range(self.backups - 1, 0, -1):
            older = self.path.with_name(f"{self.path.name}.{i}")
            if older.exists():
                older.replace(self.path.with_name(f"{self.path.name}.{i + 1}"))
        if self.backups > 0:
            self.path.replace(self.path.with_name(f"{self.path.name}.1"))
        else:
            self.path.unlink(missing_ok=True)
        self._fd = self._open()
        self._size = 0

    def close(self) -> None:
        if self._fd >= 0:
            os.close(self._fd)
            self._fd = -1


LAST_WORDS = 5  # lines of a process's output kept with its end
NOTE = "--- dura: "  # a line of dura's own in a log (see ComponentProcess.note)


def last_words(lines: list[str], keep: int = LAST_WORDS) -> tuple[str, ...]:
    """What a process said last, to show with its end: the end of its last Python
    traceback (the failing line and the exception) if it printed one, else its last
    ``keep`` lines (dura's own notes left out)."""
    own = [line for line in lines if line.strip() and not line.startswith(NOTE)]
    starts = [
        i for i, line in enumerate(own) if line.startswith("Traceback (most recent call last)")
    ]
    if not starts:
        return tuple(own[-keep:])
    traceback = own[starts[-1] + 1 :]
    frames = [i for i, line in enumerate(traceback) if line.startswith("  File ")]
    shown = traceback[frames[-1] :] if frames else traceback
    # the exception's lines are those that follow the last frame's source
    return tuple(shown[-keep:])


def tail(path: Path, lines: int) -> list[str]:
    """The last lines of a log file (none if it does not exist)."""
    if lines <= 0 or not path.is_file():
        return []
    with path.open("r", encoding="utf-8", errors="replace") as f:
        return [line.rstrip("\n") for line in deque(f, maxlen=lines)]
