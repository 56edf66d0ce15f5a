"""Child processes that cannot outlive the thread that started them.

Every process dura starts gets ``PR_SET_PDEATHSIG = SIGKILL``: the kernel kills it as
soon as its parent *thread* ends, including when the whole parent is SIGKILLed. Start
children from a thread that lives as long as they should.
"""

from __future__ import annotations

import ctypes
import functools
import os
import signal
import subprocess
import sys
from collections.abc import Mapping, Sequence
from pathlib import Path

from knowledge.description import PYTHONS

_libc = ctypes.CDLL(None, use_errno=True)
_PR_SET_PDEATHSIG = 1
_SIGKILL = int(signal.SIGKILL)


def _die_with_parent(parent: int, signum: int) -> None:
    """Runs in the child between fork and exec: no imports, no locks, no allocations."""
    _libc.prctl(_PR_SET_PDEATHSIG, signum, 0, 0, 0)
    if os.getppid() != parent:  # the parent died before prctl took effect
        os._exit(1)


def command(argv: Sequence[str]) -> list[str]:
    """An argv in which ``python``/``python3`` means this very interpreter."""
    args = list(argv)
    if args and args[0] in PYTHONS:
        args[0] = sys.executable
    return args


def spawn(
    argv: Sequence[str],
    *,
    cwd: Path | None = None,
    env: Mapping[str, str] | None = None,
    stdout: int | None = None,
    own_group: bool = False,
    parent_death: int = _SIGKILL,
) -> subprocess.Popen[bytes]:
    """Start ``argv`` (never through a shell); stderr goes where stdout goes.

    Args:
        stdout: a file descriptor for the child's stdout and stderr (default: ours).
        own_group: make the child the leader of a new process group, so that the
            group can be signalled as a whole (see :func:`signal_group`).
        parent_death: the signal the child gets when this thread ends (SIGKILL; a
            child that cleans up after itself, as the supervisor does, takes SIGHUP).

    Raises:
        OSError: the program cannot be run (missing, not executable, bad cwd).
    """
    return subprocess.Popen(
        command(argv),
        cwd=cwd,
        env=dict(env) if env is not None else None,
        stdin=subprocess.DEVNULL,
        stdout=stdout,
        stderr=subprocess.STDOUT if stdout is not None else None,
        process_group=0 if own_group else None,
        preexec_fn=functools.partial(_die_with_parent, os.getpid(), parent_death),  # noqa: PLW1509
    )


def signal_group(pgid: int, signum: int) -> bool:
    """Send a signal to a process group; False if the group is gone."""
    try:
        os.killpg(pgid, signum)
    except (ProcessLookupError, PermissionError):
        return False
    return True


def exit_status(returncode: int) -> tuple[int | None, int | None]:
    """A Popen return code as (exit code, signal): negative means killed by a signal."""
    return (returncode, None) if returncode >= 0 else (None, -returncode)


def describe_exit(exit_code: int | None, signum: int | None) -> str:
    """``exited with code 1`` or ``killed by SIGKILL``."""
    if signum is not None:
        try:
            return f"killed by {signal.Signals(signum).name}"
        except ValueError:
            return f"killed by signal {signum}"
    return f"exited with code {exit_code}"
