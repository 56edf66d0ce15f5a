"""One executive per knowledge base, and the end of what a killed one left behind.

An executive holds an exclusive ``flock`` on ``<database>.lock`` beside its knowledge
base while it runs, and one on the knowledge base file itself, whatever path names it
(a lock belongs to the file, not to its name: a hard link is the same file); a
``--db`` that is a symbolic link is refused, so that each knowledge base has one lock
file, beside the real file. The kernel drops the lock when the process ends, however it ends,
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
        self.holder = holder
        self.holder_name = holder if holder == "executive" else f"{holder} process"
        self.run_id = uuid.uuid4().hex
        self.predecessor: str | None = None  # the run that held the lock before
        self._fd: int | None = None
        self._file: int | None = None  # the knowledge base file's own lock (executive)

    def acquire(self) -> RunLock:
        """Take the lock and record this run in it.

        Raises:
            KnowledgeError: another executive holds it (its pid in the message), the
                knowledge base is named by a symbolic link, or a file cannot be opened.
        """
        if self.database.is_symlink():
            raise KnowledgeError(
                f"{self.database}: the knowledge base is a symbolic link (to "
                f"{self.database.resolve()}): give its real path"
            )
        try:
            self.path.parent.mkdir(parents=True, exist_ok=True)
            fd = os.open(self.path, os.O_RDWR | os.O_CREAT | os.O_CLOEXEC, 0o600)
        except OSError as e:
            raise KnowledgeError(f"{self.path}: cannot open the lock file: {e.strerror}") from e
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
            if self.database.exists():
                self.hold_file()
        except (BlockingIOError, KnowledgeError):
            holder = _read(fd).get("pid", "unknown")
            os.close(fd)
            raise KnowledgeError(
                f"{self.database}: the knowledge base is in use by another {self.holder_name} "
                f"(pid {holder}); stop it first or give this one another --db"
            ) from None
        except OSError as e:
            os.close(fd)
            raise KnowledgeError(f"{self.database}: cannot open it: {e.strerror}") from e
        previous = _read(fd).get("run")
        self.predecessor = previous if isinstance(previous, str) else None
        record = {"pid": os.getpid(), "run": self.run_id, "started": time.time()}
        os.ftruncate(fd, 0)
        os.pwrite(fd, (json.dumps(record) + "\n").encode(), 0)
        self._fd = fd
        return self

    def hold_file(self) -> None:
        """(The executive) Lock the knowledge base file itself, once it is there: a new
        one is locked when it has been made, before anything is stored in it.

        Raises:
            KnowledgeError: another process holds it, under whatever name.
        """
        if self.holder == "executive" and self._file is None:
            try:
                self._file = _lock_file(self.database)
            except BlockingIOError:
                raise KnowledgeError(
                    f"{self.database}: the knowledge base is in use by another executive "
                    "(under another name); stop it first or give this one another --db"
                ) from None

    def release(self) -> None:
        """Drop the lock (the file stays: the next run reads its predecessor there)."""
        for fd in (self._file, self._fd):
            if fd is not None:
                os.close(fd)  # closing the only descriptor drops the flock
        self._fd = self._file = None

    def __enter__(self) -> RunLock:
        return self.acquire()

    def __exit__(self, *exc: object) -> None:
        self.release()


def _lock_file(database: Path) -> int:
    """An exclusive ``flock`` on the knowledge base file itself. SQLite's own locks are
    ``fcntl`` locks, which a ``flock`` does not touch.

    Raises:
        BlockingIOError: another process holds it, under whatever name.
    """
    fd = os.open(database, os.O_RDONLY | os.O_CLOEXEC)
    try:
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except BaseException:
        os.close(fd)
        raise
    return fd


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
