"""What a long command is doing now: one live line on a terminal, nothing elsewhere.

``dura run``, ``dura validate`` and ``dura plan --offline`` can take seconds (longer
on a busy machine). On a terminal they show what they do now and for how long, on
standard error, redrawn in place and taken away before the result is printed. Off a
terminal (a pipe, a file, a test) and with ``--json`` they print nothing extra.
"""

from __future__ import annotations

import shutil
import sys
import threading
import time
from types import TracebackType
from typing import TextIO

TICK = 0.5  # seconds between two redraws of the clock


class LiveLine:
    """A line that says what a command does now, with the seconds it has taken.

    Args:
        shown: draw at all (``False`` with ``--json``); drawn only on a terminal.
        out: where to draw (standard error).
    """

    def __init__(self, *, shown: bool = True, out: TextIO | None = None) -> None:
        self.out = out or sys.stderr
        self.live = shown and self.out.isatty()
        self.activity = ""
        self._since = time.monotonic()
        self._drawn = ""
        self._lock = threading.Lock()
        self._stop = threading.Event()
        self._ticker: threading.Thread | None = None

    def doing(self, activity: str) -> None:
        """Say what the command does now (its clock starts again)."""
        with self._lock:
            self.activity, self._since = activity, time.monotonic()
            self._draw()

    def __enter__(self) -> LiveLine:
        if self.live:
            self._ticker = threading.Thread(target=self._tick, name="live-line", daemon=True)
            self._ticker.start()
        return self

    def __exit__(
        self,
        kind: type[BaseException] | None,
        error: BaseException | None,
        trace: TracebackType | None,
    ) -> None:
        self._stop.set()
        if self._ticker is not None:
            self._ticker.join()
        with self._lock:
            self.clear()

    def clear(self) -> None:
        """Take the line away (before the command prints its result)."""
        if self._drawn:
            self.out.write("\r\x1b[K")
            self.out.flush()
            self._drawn = ""

    def _tick(self) -> None:
        while not self._stop.wait(TICK):
            with self._lock:
                self._draw()

    def _draw(self) -> None:
        if not self.live or not self.activity:
            return
        seconds = int(time.monotonic() - self._since)
        line = f"dura: {self.activity}" + (f" ({seconds} s)" if seconds else "")
        if line == self._drawn:
            return
        width = shutil.get_terminal_size().columns
        self.out.write("\r" + line[: width - 1] + "\x1b[K")
        self.out.flush()
        self._drawn = line
