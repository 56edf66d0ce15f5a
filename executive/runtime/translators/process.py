"""The ``process`` translator: any program, driven through its process.

A functionality's program starts on start and ends on stop (SIGTERM, SIGKILL after
:data:`STOP_GRACE` seconds); pause and resume are SIGSTOP and SIGCONT. A behavior's
program runs once per goal: ``{field}`` in its arguments is replaced by the goal's
field (``{{`` for a brace), the whole goal is in ``DURA_GOAL`` (JSON), and the exit
code is the result: 0 succeeds, anything else fails. Parameters are in
``DURA_PARAMS`` (JSON).
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import threading
from typing import Any

from executive.runtime.spawn import describe_exit, exit_status, spawn
from executive.runtime.translator import Translator
from executive.sdk import Behavior, GoalCancelled, GoalFailed

STOP_GRACE = 2.0
POLL = 0.05  # how often a running goal looks for a cancellation


class ProcessTranslator(Translator):
    name = "process"

    _program: subprocess.Popen[bytes] | None = None
    _stopping = False

    def _spawn(self, argv: list[str], **env: str) -> subprocess.Popen[bytes]:
        self.log.info("starting %s", " ".join(argv))
        return spawn(argv, env={**os.environ, **env})

    def start(self, params: dict[str, Any]) -> None:
        self._program = program = self._spawn(self.argv, DURA_PARAMS=json.dumps(params))
        threading.Thread(target=self._watch, args=(program,), daemon=True).start()

    def exited(self) -> bool:
        """Tell whether the program was started and has ended."""
        program = self._program
        return program is not None and program.poll() is not None

    def _watch(self, program: subprocess.Popen[bytes]) -> None:
        returncode = program.wait()
        if not self._stopping:
            self.on_exit(returncode)

    def _signal(self, signum: int) -> None:
        program = self._program
        if program is not None and program.returncode is None:
            program.send_signal(signum)

    def pause(self) -> None:
        self._signal(signal.SIGSTOP)

    def resume(self) -> None:
        self._signal(signal.SIGCONT)

    def stop(self) -> None:
        self._stopping = True
        self._end()

    def _end(self) -> None:
        program = self._program
        if program is None or program.poll() is not None:
            return
        program.terminate()
        program.send_signal(signal.SIGCONT)  # a paused program must run to see SIGTERM
        try:
            program.wait(STOP_GRACE)
        except subprocess.TimeoutExpired:
            program.kill()
            program.wait()

    def execute(self, goal: dict[str, Any], behavior: Behavior) -> dict[str, Any]:
        try:
            argv = [arg.format_map(goal) for arg in self.argv]
        except (KeyError, ValueError, IndexError) as e:
            raise GoalFailed(f"cannot fill in the program's arguments from the goal: {e}") from e
        self._program = program = self._spawn(argv, DURA_GOAL=json.dumps(goal))
        try:
            while program.poll() is None:
                behavior.checkpoint()
                try:
                    program.wait(POLL)
                except subprocess.TimeoutExpired:
                    continue
        except GoalCancelled:
            self._end()
            raise
        if program.returncode != 0:
            raise GoalFailed(f"{argv[0]} {describe_exit(*exit_status(program.returncode))}")
        return {"exit_code": 0}
