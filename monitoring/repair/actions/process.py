"""Run a process from an argv list (never through a shell)."""

from __future__ import annotations

import os
import signal
import subprocess

from knowledge.errors import DuraError
from knowledge.yamlsource import Section, describe
from monitoring.repair.action import Action, ActionContext, Firing


class ProcessAction(Action):
    """Run ``process`` (an argv list) in the robot's folder; kill it after ``timeout``."""

    type = "process"

    def __init__(self, argv: tuple[str, ...], timeout: float) -> None:
        super().__init__(timeout)
        self.argv = argv

    @classmethod
    def configure(cls, entry: Section, timeout: float) -> Action:
        node = entry.node("process")
        if node is None:
            entry.report.error(entry.line, f"{entry.what} has no 'process' (an argv list)")
            return cls((), timeout)
        if not hasattr(node, "value") or not isinstance(node.value, list):
            entry.report.error(
                entry.key_line("process"),
                f"'process' of {entry.what} must be an argv list such as [kill, -9, '1234'], "
                f"not {describe(node)} (dura never runs a shell)",
            )
            return cls((), timeout)
        argv = entry.texts("process")
        if not argv:
            entry.report.error(entry.key_line("process"), f"'process' of {entry.what} is empty")
        return cls(argv, timeout)

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
