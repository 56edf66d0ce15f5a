"""Write a line to a log file (or to dura's log when no file is named)."""

from __future__ import annotations

import logging
import time
from pathlib import Path

from knowledge.yamlsource import Section
from monitoring.repair.action import Action, ActionContext, Firing

log = logging.getLogger("dura.repair")


class LogAction(Action):
    """Append ``message`` with a time stamp to ``file`` (relative to the robot's folder)."""

    type = "log"

    def __init__(self, message: str, file: str | None, timeout: float) -> None:
        super().__init__(timeout)
        self.message = message
        self.file = file

    @classmethod
    def configure(cls, entry: Section, timeout: float) -> Action:
        message = entry.text("message") or entry.text("log_entry") or "rule $rule fired"
        return cls(message, entry.text("file") or entry.text("log_file"), timeout)

    def _run(self, context: ActionContext, firing: Firing) -> None:
        text = firing.fill(self.message)
        if self.file is None:
            log.warning("%s", text)
            return
        path = context.folder / Path(self.file)
        path.parent.mkdir(parents=True, exist_ok=True)
        stamp = time.strftime("%Y-%m-%d %H:%M:%S", time.localtime(firing.stamp or time.time()))
        with path.open("a", encoding="utf-8") as f:
            f.write(f"{stamp} {text}\n")

    def describe(self) -> str:
        return f"log to {self.file or 'the dura log'}"
