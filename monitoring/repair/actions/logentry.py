"""Write a line to a log file (or to dura's log when no file is named)."""

from __future__ import annotations

import logging
import time
from dataclasses import dataclass
from pathlib import Path

from monitoring.repair.action import Action, ActionContext, Firing

log = logging.getLogger("dura.repair")


@dataclass(frozen=True, kw_only=True)
class LogAction(Action):
    """Append ``message`` with a time stamp to ``file`` (relative to the robot's folder);
    tug's ``log_entry`` and ``log_file`` say the same."""

    type = "log"
    message: str | None = None
    log_entry: str | None = None
    file: str | None = None
    log_file: str | None = None

    @property
    def text(self) -> str:
        return self.message or self.log_entry or "rule $rule fired"

    @property
    def path(self) -> str | None:
        return self.file or self.log_file

    def _run(self, context: ActionContext, firing: Firing) -> None:
        text = firing.fill(self.text)
        if self.path is None:
            log.warning("%s", text)
            return
        path = context.folder / Path(self.path)
        path.parent.mkdir(parents=True, exist_ok=True)
        stamp = time.strftime("%Y-%m-%d %H:%M:%S", time.localtime(firing.stamp or time.time()))
        with path.open("a", encoding="utf-8") as f:
            f.write(f"{stamp} {text}\n")

    def describe(self) -> str:
        return f"log to {self.path or 'the dura log'}"
