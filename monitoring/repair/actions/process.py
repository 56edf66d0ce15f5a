"""Run a process from an argv list (never through a shell)."""

from __future__ import annotations

import os
import signal
import subprocess
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Annotated, Any

from knowledge.conventions import Convert, Key, OneOrMore
from knowledge.errors import DuraError
from knowledge.typed_reader import MISSING, Entry, Place, read_value
from monitoring.repair.action import Action, ActionContext, Firing


def _argv(value: Any, place: Place) -> Any:
    """An argv list; a text or a number is refused (dura never runs a shell)."""
    what = f"'process' of {place.entry.what}"
    if not isinstance(value, list | Mapping):
        shown = place.source.describe(value, place.path)
        place.entry.error(
            "process",
            f"{what} must be an argv list such as [kill, -9, '1234'], not {shown} "
            "(dura never runs a shell)",
        )
        return MISSING
    argv = read_value(Annotated[tuple[str, ...], OneOrMore()], value, place)
    if argv is MISSING or not argv:  # nothing to run (a mapping, reported, is no list)
        place.entry.error("process", f"{what} is empty")
    return argv


@dataclass(frozen=True, kw_only=True)
class ProcessAction(Action):
    """Run ``process`` (an argv list) in the robot's folder; kill it after ``timeout``."""

    type = "process"
    argv: Annotated[tuple[str, ...], Key("process"), Convert(_argv)] = ()

    def after_read(self, entry: Entry) -> ProcessAction:
        if not entry.has("process"):
            entry.error(None, f"{entry.what} has no 'process' (an argv list)")
        return self

    def _run(self, context: ActionContext, firing: Firing) -> None:
        argv = [firing.fill(a) for a in self.argv]
        process = subprocess.Popen(argv, cwd=context.folder, start_new_session=True)
        try:
            code = process.wait(self.timeout)
        except subprocess.TimeoutExpired:
            os.killpg(process.pid, signal.SIGKILL)
            process.wait()
            raise DuraError(
                f"process {argv} did not end within {self.timeout:g} s (killed)"
            ) from None
        if code != 0:
            raise DuraError(f"process {argv} exited with {code}")

    def describe(self) -> str:
        return f"run {' '.join(self.argv)}"
