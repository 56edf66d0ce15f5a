"""The head of a component's process group: whatever happens, the whole tree ends.

The launcher starts every component under this small supervisor, in a process group of
the supervisor's own::

    python -I -S supervisor.py EXECUTIVE_PID GRACE -- PROGRAM [ARG ...]

The supervisor is the child subreaper of everything below it (an orphaned grandchild
becomes its child, not init's), starts the program as its only child, reaps orphans,
and when the program ends it ends every process left in its group and below it, then
exits the way the program did (the same exit code, or killed by the same signal), so
the launcher sees the program's end.

It outlives the executive only briefly: its parent-death signal is SIGHUP (catchable,
unlike the SIGKILL the program gets if the supervisor dies), on which it asks the group
to stop (SIGTERM), waits ``GRACE`` seconds at most, and kills what is left. SIGUSR1
from the launcher kills the whole tree at once (a stop that SIGTERM did not end).
SIGTERM and SIGINT sent to the group are for the program; the supervisor stays to
clean up after it.

This file runs as a script with the standard library only (``-I -S``: a fast start, no
site-packages), never imported by dura.
"""

from __future__ import annotations

import contextlib
import ctypes
import os
import resource
import signal
import sys
import time

PR_SET_PDEATHSIG = 1
PR_SET_CHILD_SUBREAPER = 36
CLEANUP_LIMIT = 5.0  # seconds to keep killing a tree that keeps forking
POLL = 0.01

_libc = ctypes.CDLL(None, use_errno=True)


def _stat(pid: int) -> tuple[str, int, int]:
    """A process's state, parent and process group ("" when it is gone)."""
    try:
        with open(f"/proc/{pid}/stat", "rb") as f:
            text = f.read()
    except OSError:
        return "", 0, 0
    fields = text[text.rindex(b")") + 2 :].split()
    return fields[0].decode(), int(fields[1]), int(fields[2])


def _ours(me: int, ppid: int, group: int) -> bool:
    return me in (ppid, group)


class Supervisor:
    """The program's process, its end, and the ends of everything below it.

    Args:
        executive: the pid of the executive that started the supervisor.
        grace: seconds the tree gets to stop after the executive died.
        program: the program and its arguments.
    """

    def __init__(self, executive: int, grace: float, program: list[str]) -> None:
        self.executive = executive
        self.grace = grace
        self.program = program
        self.me = os.getpid()
        self.pid = 0  # the program's, once started
        self.status: int | None = None  # its wait status, once reaped

    def run(self) -> None:
        """Start the program, reap what comes, end everything once it ends."""
        signal.signal(signal.SIGHUP, self._parent_gone)
        signal.signal(signal.SIGUSR1, self._kill_now)
        for signum in (signal.SIGTERM, signal.SIGINT):  # for the program, not for us
            signal.signal(signum, lambda *_: None)
        _libc.prctl(PR_SET_CHILD_SUBREAPER, 1, 0, 0, 0)
        _libc.prctl(PR_SET_PDEATHSIG, signal.SIGHUP, 0, 0, 0)
        if os.getppid() != self.executive:  # it died before the signal was set
            os._exit(1)
        self.pid = self._start()
        while self.status is None:
            try:
                pid, status = os.waitpid(-1, 0)
            except ChildProcessError:
                break
            if pid == self.pid:
                self.status = status
        self._end_everything()
        self._exit_as_the_program()

    def _start(self) -> int:
        pid = os.fork()
        if pid:
            return pid
        try:  # the program: default signal handling, and it dies with the supervisor
            for signum in (signal.SIGHUP, signal.SIGTERM, signal.SIGINT, signal.SIGUSR1):
                signal.signal(signum, signal.SIG_DFL)
            _libc.prctl(PR_SET_PDEATHSIG, signal.SIGKILL, 0, 0, 0)
            if os.getppid() != self.me:
                os._exit(1)
            os.execvp(self.program[0], self.program)  # noqa: S606 - an argv, never a shell
        except OSError as e:
            os.write(2, f"dura supervisor: cannot run {self.program[0]!r}: {e.strerror}\n".encode())
        finally:
            os._exit(127)

    def _members(self) -> list[int]:
        """Processes to end: in this group or children of this process (not zombies)."""
        found = []
        for entry in os.listdir("/proc"):
            if not entry.isdigit() or int(entry) == self.me:
                continue
            state, ppid, group = _stat(int(entry))
            if state and state != "Z" and _ours(self.me, ppid, group):
                found.append(int(entry))
        return found

    def _kill(self, pid: int) -> None:
        """SIGKILL a member, sure that it is the same process (a pid may be reused)."""
        try:
            fd = os.pidfd_open(pid)
        except OSError:
            return
        try:
            _, ppid, group = _stat(pid)
            if _ours(self.me, ppid, group):
                signal.pidfd_send_signal(fd, signal.SIGKILL)
        except OSError:
            pass
        finally:
            os.close(fd)

    def _reap(self) -> bool:
        """Reap every child that has ended; whether one is left."""
        while True:
            try:
                pid, status = os.waitpid(-1, os.WNOHANG)
            except ChildProcessError:
                return False
            if pid == 0:
                return True
            if pid == self.pid:
                self.status = status

    def _end_everything(self) -> None:
        """Kill every process of the tree (those that leave the group come back to us
        as orphans) and reap them."""
        deadline = time.monotonic() + CLEANUP_LIMIT
        while left := self._members():
            for pid in left:
                self._kill(pid)
            if time.monotonic() > deadline:
                break
            self._reap()
            time.sleep(POLL / 10)
        while self._reap() and time.monotonic() < deadline:
            time.sleep(POLL / 10)

    def _exit_as_the_program(self) -> None:
        """Exit the way the program did."""
        status = self.status
        if status is None:
            os._exit(1)
        if os.WIFSIGNALED(status):
            signum = os.WTERMSIG(status)
            with contextlib.suppress(OSError, ValueError):
                resource.setrlimit(resource.RLIMIT_CORE, (0, 0))  # no core of ours
                signal.signal(signum, signal.SIG_DFL)
            os.kill(self.me, signum)
            os._exit(128 + signum)
        os._exit(os.waitstatus_to_exitcode(status))

    def _kill_now(self, *_: object) -> None:
        """SIGUSR1: end the whole tree now."""
        self._end_everything()
        self._exit_as_the_program()

    def _parent_gone(self, *_: object) -> None:
        """SIGHUP (the executive died): ask the group to stop, then end everything."""
        for signum in (signal.SIGTERM, signal.SIGCONT):  # a paused program must see SIGTERM
            with contextlib.suppress(OSError):
                os.killpg(0, signum)
        deadline = time.monotonic() + self.grace
        while self.status is None and self._reap() and time.monotonic() < deadline:
            time.sleep(POLL)
        self._end_everything()
        self._exit_as_the_program()


def main(argv: list[str]) -> None:
    if len(argv) < 5 or argv[3] != "--":
        os.write(2, b"usage: supervisor.py EXECUTIVE_PID GRACE -- PROGRAM [ARG ...]\n")
        os._exit(2)
    Supervisor(int(argv[1]), float(argv[2]), argv[4:]).run()


if __name__ == "__main__":
    main(sys.argv)
