"""One executive per knowledge base, and the end of what a killed one left behind.

An executive holds an exclusive ``flock`` on ``<database>.lock`` beside its knowledge
base while it runs. The kernel drops the lock when the process ends, however it ends,
so a killed executive never leaves it stuck; a second executive on the same knowledge
base finds it held and refuses to start, naming the pid the file records.

Each run has an id, recorded in the lock file and set as ``DURA_RUN`` in the
environment of every component the run starts (their children inherit it). The next
executive on the knowledge base ends every process still marked with its
predecessor's run: normally none (each component's supervisor ends its tree when the
executive dies), but a supervisor killed together with its executive leaves its
program's children behind. A process is identified by its environment, read through a
pidfd, so a reused pid is never mistaken for one of ours.
"""

from __future__ import annotations

import contextlib
import fcntl
import json
import logging
import os
import signal
import time
import uuid
from pathlib import Path

from knowledge.errors import KnowledgeError

log = logging.getLogger("dura.launcher")

ENV_RUN = "DURA_RUN"
CLEANUP_LIMIT = 5.0  # seconds to keep ending a predecessor's processes


class RunLock:
    """The lock of one executive's run on a knowledge base (see the module docstring).

    Args:
        database: the knowledge base file; the lock is ``<database>.lock`` beside it.
        holder: who holds it: ``executive``, or the group of services that runs the
            components in a process of its own (``tasks``: ``<database>.tasks.lock``).
    """

    def __init__(self, database: Path, holder: str = "executive") -> None:
        suffix = ".lock" if holder == "executive" else f".{holder}.lock"
        self.database = database
        self.path = database.with_name(database.name + suffix)
        self.holder_name = holder if holder == "executive" else f"{holder} process"
        self.run_id = uuid.uuid4().hex
        self.predecessor: str | None = None  # the run that held the lock before
        self._fd: int | None = None

    def acquire(self) -> RunLock:
        """Take the lock and record this run in it.

        Raises:
            KnowledgeError: another executive holds it (its pid in the message), or the
                lock file cannot be written.
        """
        try:
            self.path.parent.mkdir(parents=True, exist_ok=True)
            fd = os.open(self.path, os.O_RDWR | os.O_CREAT | os.O_CLOEXEC, 0o600)
        except OSError as e:
            raise KnowledgeError(f"{self.path}: cannot open the lock file: {e.strerror}") from e
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            holder = _read(fd).get("pid", "unknown")
            os.close(fd)
            raise KnowledgeError(
                f"{self.database}: the knowledge base is in use by another {self.holder_name} "
                f"(pid {holder}); stop it first or give this one another --db"
            ) from None
        previous = _read(fd).get("run")
        self.predecessor = previous if isinstance(previous, str) else None
        record = {"pid": os.getpid(), "run": self.run_id, "started": time.time()}
        os.ftruncate(fd, 0)
        os.pwrite(fd, (json.dumps(record) + "\n").encode(), 0)
        self._fd = fd
        return self

    def release(self) -> None:
        """Drop the lock (the file stays: the next run reads its predecessor there)."""
        if self._fd is not None:
            os.close(self._fd)  # closing the only descriptor drops the flock
            self._fd = None

    def __enter__(self) -> RunLock:
        return self.acquire()

    def __exit__(self, *exc: object) -> None:
        self.release()


def _read(fd: int) -> dict[str, object]:
    with contextlib.suppress(OSError, ValueError):
        data = json.loads(os.pread(fd, 4096, 0) or b"{}")
        if isinstance(data, dict):
            return data
    return {}


def end_leftovers(run_id: str) -> int:
    """SIGKILL every process whose environment marks it as started by run ``run_id``;
    returns how many there were."""
    marker = f"{ENV_RUN}={run_id}".encode()
    ended: set[int] = set()
    deadline = time.monotonic() + CLEANUP_LIMIT
    while time.monotonic() < deadline:
        found = [pid for pid in _pids() if pid not in ended and _marked(pid, marker)]
        if not found:
            break
        for pid in found:
            if _kill_if_marked(pid, marker):
                ended.add(pid)
        time.sleep(0.01)
    if ended:
        log.warning("ended %d processes a killed executive left (run %s)", len(ended), run_id)
    return len(ended)


def _pids() -> list[int]:
    me = os.getpid()
    return [int(e) for e in os.listdir("/proc") if e.isdigit() and int(e) != me]


def _marked(pid: int, marker: bytes) -> bool:
    try:
        with open(f"/proc/{pid}/environ", "rb") as f:
            return marker in f.read().split(b"\0")
    except OSError:  # gone, a zombie, or another user's
        return False


def _kill_if_marked(pid: int, marker: bytes) -> bool:
    """SIGKILL the process if it is (through its pidfd, so surely the same) marked."""
    try:
        fd = os.pidfd_open(pid)
    except OSError:
        return False
    try:
        if not _marked(pid, marker):
            return False
        signal.pidfd_send_signal(fd, signal.SIGKILL)
        return True
    except OSError:
        return False
    finally:
        os.close(fd)
