"""Component processes as the operating system sees them: forked, pumped, reaped.

This module owns the launcher thread. It lives as long as the launcher and forks every
component process, because a child gets ``PR_SET_PDEATHSIG`` and so learns of the end
of the *thread* that forked it (see :mod:`executive.runtime.spawn`). Each component
runs under a supervisor (:mod:`executive.runtime.supervisor`) at the head of its
process group, which ends the component's whole tree, grandchildren included, when the
component ends or the executive dies. The thread waits on a pidfd per child, so an exit
is known at once: it kills whatever is left of the child's process group, reaps the
child, drains its output and hands the exit to the owner of the process
(:mod:`executive.runtime.component_lifecycle`). Each child's stdout and stderr go through a pipe
into ``<name>.log``, rotated by size.

What a process means (ready, stopping, failed) is not decided here: this module knows
pids, file descriptors and log files.
"""

from __future__ import annotations

import contextlib
import errno
import logging
import os
import queue
import selectors
import shutil
import signal
import subprocess
import sys
import threading
import time
from collections.abc import Callable, Mapping, Sequence
from concurrent.futures import Future
from dataclasses import dataclass
from pathlib import Path
from typing import Any, TypeVar

from executive.runtime.logfile import LogFile, last_words, tail
from executive.runtime.spawn import command, exit_status, signal_group, spawn
from knowledge.errors import ComponentError

log = logging.getLogger("dura.launcher")

T = TypeVar("T")

LOG_LINES_READ = 60  # lines of its log read at a process's end for its last words
SUPERVISOR = Path(__file__).with_name("supervisor.py")


@dataclass(eq=False)
class ComponentProcess:
    """One forked component: the supervisor's pid (the head of its process group, the
    launcher's child), its pidfd, output pipe and log file, and the program's pid."""

    name: str
    pid: int
    popen: subprocess.Popen[bytes]
    pidfd: int
    pipe: int
    log: LogFile
    program_pid: int | None = None
    reaped: bool = False
    output: tuple[str, ...] = ()  # what it said last (logfile.last_words), once reaped

    def program(self) -> int:
        """The component's own process, below its supervisor (the supervisor's pid
        while the program has not been forked yet)."""
        if self.program_pid is None and not self.reaped:
            self.program_pid = first_child(self.pid)
        return self.program_pid or self.pid

    def note(self, text: str) -> None:
        """Write a line of dura's own into the process's log (``--- dura: ...``)."""
        self.log.write(f"--- dura: {text} {time.strftime('%Y-%m-%d %H:%M:%S')}\n".encode())

    def finish(self, text: str) -> None:
        """Write the last line of dura's own and close the log."""
        self.note(text)
        self.log.close()


ExitHandler = Callable[[ComponentProcess, int | None, int | None], None]
"""Called on the launcher thread with a reaped process, its exit code and its signal."""


class ProcessThread:
    """The launcher thread: forks component processes, pumps their output, reaps them.

    Args:
        log_dir: where ``<name>.log`` files go.
        log_max_bytes, log_backups: log rotation.
        on_exit: told of every reaped process, its output drained; it ends the log
            with :meth:`ComponentProcess.finish` (closed anyway if ``on_exit`` fails).
        grace: seconds a component's tree gets to stop (SIGTERM) once the executive
            died, before its supervisor kills it.
    """

    def __init__(
        self,
        log_dir: Path,
        *,
        log_max_bytes: int,
        log_backups: int,
        on_exit: ExitHandler,
        grace: float = 1.0,
    ) -> None:
        self.log_dir = log_dir
        self.grace = grace
        self.log_max_bytes = log_max_bytes
        self.log_backups = log_backups
        self._on_exit = on_exit
        self._selector = selectors.DefaultSelector()
        self._wake = os.eventfd(0, os.EFD_CLOEXEC | os.EFD_NONBLOCK)
        self._calls: queue.SimpleQueue[tuple[Callable[[], Any], Future[Any]]] = queue.SimpleQueue()
        self._running = False
        self._thread = threading.Thread(target=self._loop, name="launcher", daemon=True)

    def open(self) -> None:
        self._selector.register(self._wake, selectors.EVENT_READ, self._run_calls)
        self._running = True
        self._thread.start()

    def close(self) -> None:
        """End the thread (stop the processes first: they would die with it)."""
        self.call(self._finish)
        self._thread.join()
        self._selector.close()
        os.close(self._wake)

    def log_path(self, name: str) -> Path:
        return self.log_dir / f"{name}.log"

    def call(self, fn: Callable[[], T]) -> T:
        """Run ``fn`` on the launcher thread and return its result (or raise)."""
        if not self._running:
            raise ComponentError("the launcher is closed")
        outcome: Future[T] = Future()
        self._calls.put((fn, outcome))
        os.eventfd_write(self._wake, 1)
        return outcome.result()

    def fork(
        self, name: str, argv: Sequence[str], *, cwd: Path, env: Mapping[str, str]
    ) -> ComponentProcess:
        """Start a program under its supervisor in a group of its own, its output into
        its log file.

        Only on the launcher thread (inside :meth:`call`): the supervisor learns of the
        end of the thread that forked it.

        Raises:
            OSError: the program cannot be run.
        """
        if threading.current_thread() is not self._thread:
            raise RuntimeError("fork() runs on the launcher thread only (use call())")
        program = command(argv)
        runnable(program[0], cwd, env)
        logfile = LogFile(
            self.log_path(name), max_bytes=self.log_max_bytes, backups=self.log_backups
        )
        head = [sys.executable, "-I", "-S", str(SUPERVISOR), str(os.getpid()), f"{self.grace:g}"]
        read_end, write_end = os.pipe()
        try:
            popen = spawn(
                [*head, "--", *program],
                cwd=cwd,
                env={**env, "PYTHONUNBUFFERED": "1"},  # output reaches the log as it comes
                stdout=write_end,
                own_group=True,
                parent_death=signal.SIGHUP,  # the supervisor ends the tree, then itself
            )
        except OSError:
            os.close(read_end)
            logfile.close()
            raise
        finally:
            os.close(write_end)
        os.set_blocking(read_end, False)
        process = ComponentProcess(
            name, popen.pid, popen, os.pidfd_open(popen.pid), read_end, logfile
        )
        process.note(f"started {name} (supervisor pid {popen.pid})")
        self._selector.register(process.pidfd, selectors.EVENT_READ, lambda: self._reap(process))
        self._selector.register(read_end, selectors.EVENT_READ, lambda: self._pump(process))
        return process

    def signal(self, process: ComponentProcess, signum: int, *, group: bool = True) -> None:
        """Signal a process's group (or only its supervisor) unless it has been reaped
        (on the launcher thread, which reaps: a reaped pid may belong to someone else)."""

        def send() -> None:
            if process.reaped:
                return
            if group:
                signal_group(process.pid, signum)
            else:
                with contextlib.suppress(OSError):
                    signal.pidfd_send_signal(process.pidfd, signum)

        self.call(send)

    def _run_calls(self) -> None:
        with contextlib.suppress(BlockingIOError):
            os.eventfd_read(self._wake)
        while True:
            try:
                fn, outcome = self._calls.get_nowait()
            except queue.Empty:
                return
            try:
                outcome.set_result(fn())
            except Exception as e:
                outcome.set_exception(e)

    def _finish(self) -> None:
        self._running = False

    def _loop(self) -> None:
        while self._running:
            for key, _ in self._selector.select():
                try:
                    key.data()
                except Exception:
                    log.exception("the launcher thread failed to handle an event")
        while True:  # calls that came too late
            try:
                _, outcome = self._calls.get_nowait()
            except queue.Empty:
                return
            outcome.set_exception(ComponentError("the launcher is closed"))

    def _pump(self, process: ComponentProcess) -> None:
        """Copy what the process wrote into its log file."""
        try:
            while data := os.read(process.pipe, 65536):
                process.log.write(data)
        except BlockingIOError:
            return
        except OSError as e:
            log.warning("cannot read the output of '%s': %s", process.name, e)
        self._close_pipe(process)  # end of file: every writer has gone

    def _close_pipe(self, process: ComponentProcess) -> None:
        if process.pipe >= 0:
            self._selector.unregister(process.pipe)
            os.close(process.pipe)
            process.pipe = -1

    def _reap(self, process: ComponentProcess) -> None:
        """The process has exited: kill its group, reap it, tell the owner."""
        signal_group(process.pid, signal.SIGKILL)  # pgid == pid; reserved until reaped
        returncode = process.popen.wait()
        process.reaped = True
        self._selector.unregister(process.pidfd)
        os.close(process.pidfd)
        if process.pipe >= 0:
            self._pump(process)
            self._close_pipe(process)
        process.output = last_words(tail(process.log.path, LOG_LINES_READ))
        try:
            self._on_exit(process, *exit_status(returncode))
        finally:
            process.log.close()  # a no-op once on_exit has finished it


def runnable(program: str, cwd: Path, env: Mapping[str, str]) -> None:
    """Check that ``program`` can be run from ``cwd`` (the supervisor runs it later).

    Raises:
        OSError: it is missing or not executable, as running it would say.
    """
    if os.sep in program:
        path = cwd / program
        if not path.exists():
            raise FileNotFoundError(errno.ENOENT, os.strerror(errno.ENOENT), program)
        if path.is_dir() or not os.access(path, os.X_OK):
            raise PermissionError(errno.EACCES, os.strerror(errno.EACCES), program)
    elif shutil.which(program, path=env.get("PATH", os.defpath)) is None:
        raise FileNotFoundError(errno.ENOENT, os.strerror(errno.ENOENT), program)


def first_child(pid: int) -> int | None:
    """The oldest living child of ``pid``, from ``/proc`` (``None``: it has none)."""
    found: list[tuple[int, int]] = []
    for entry in os.listdir("/proc"):
        if not entry.isdigit():
            continue
        try:
            with open(f"/proc/{entry}/stat", "rb") as f:
                text = f.read()
        except OSError:
            continue
        fields = text[text.rindex(b")") + 2 :].split()
        if int(fields[1]) == pid and fields[0] != b"Z":
            found.append((int(fields[19]), int(entry)))
    return min(found)[1] if found else None
