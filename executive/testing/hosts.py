"""Host agents (``dura host``) as child processes, and network namespaces to put them
in: for tests and benchmarks of robots that span computers.

:class:`HostProcess` runs the agent of one host of a robot whose executive a
:class:`~executive.testing.harness.RobotProcess` runs, in the same folder (where the
executive wrote the host's credentials), and waits until it has joined.
:class:`NetworkNamespace` makes a namespace joined to this one by a veth pair, so that
an agent in it is another computer as far as the network goes: bringing the link down
is a network partition. Namespaces need root (``ip netns``); :func:`namespaces_usable`
says whether this machine allows them.
"""

from __future__ import annotations

import contextlib
import os
import subprocess
import sys
import threading
import time
import uuid
from collections.abc import Sequence
from pathlib import Path

import psutil

from executive.testing.harness import terminate
from knowledge.errors import DuraError

JOIN_TIMEOUT = 60.0  # seconds for an agent to join the executive


class HostProcess:
    """The agent of one host, as a child process.

    Args:
        description: the robot description.
        folder: the executive's folder (the host's credentials are in its ``.dura/``).
        name: the host's name in the description.
        endpoint: the executive's endpoint as the agent reaches it.
        namespace: run it in this network namespace.
        args: more arguments of ``dura host``.
    """

    def __init__(
        self,
        description: Path,
        folder: Path,
        name: str,
        endpoint: str,
        *,
        namespace: str | None = None,
        args: Sequence[str] = (),
    ) -> None:
        self.description = Path(description).resolve()
        self.folder = Path(folder)
        self.name = name
        self.endpoint = endpoint
        self.namespace = namespace
        self.args = list(args)
        self.lines: list[str] = []
        self._changed = threading.Condition()
        self._process: subprocess.Popen[str] | None = None
        self._reader: threading.Thread | None = None

    def __enter__(self) -> HostProcess:
        self.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self.stop()

    @property
    def pid(self) -> int:
        if self._process is None:
            raise DuraError(f"the agent of host '{self.name}' does not run")
        return self._process.pid

    def start(self, timeout: float = JOIN_TIMEOUT) -> None:
        """Start the agent and wait until it has joined the executive."""
        argv = [sys.executable, "-m", "executive.cli", "host", str(self.description),
                "--name", self.name, "--connect", self.endpoint, "--grace", "1",
                "--log-dir", str(self.folder / "logs" / self.name), *self.args]  # fmt: skip
        if self.namespace is not None:
            argv = ["ip", "netns", "exec", self.namespace, *argv]  # execs: the pid is the agent's
        self._process = subprocess.Popen(
            argv, cwd=self.folder, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
            env={**os.environ, "PYTHONUNBUFFERED": "1"},
        )  # fmt: skip
        self._reader = threading.Thread(target=self._read, name=f"host-{self.name}", daemon=True)
        self._reader.start()
        self.wait_for_line("joined", timeout)

    def _read(self) -> None:
        process = self._process
        if process is None or process.stdout is None:
            return
        for line in process.stdout:
            with self._changed:
                self.lines.append(line.rstrip("\n"))
                self._changed.notify_all()
        with self._changed:
            self._changed.notify_all()

    def wait_for_line(self, text: str, timeout: float = JOIN_TIMEOUT, *, after: int = 0) -> int:
        """Wait until a line of the agent's output (from line ``after`` on) holds ``text``;
        its index.

        Raises:
            DuraError: it did not come in time, or the agent ended first.
        """
        deadline = time.monotonic() + timeout
        with self._changed:
            while True:
                found = [i for i, line in enumerate(self.lines) if i >= after and text in line]
                if found:
                    return found[0]
                ended = self._process is None or self._process.poll() is not None
                left = deadline - time.monotonic()
                if ended or left <= 0:
                    output = "\n".join(self.lines[-20:])
                    raise DuraError(f"host '{self.name}': no '{text}' in its output:\n{output}")
                self._changed.wait(min(left, 0.2))

    def programs(self) -> list[psutil.Process]:
        """The component programs this agent runs (below their supervisors)."""
        with contextlib.suppress(psutil.NoSuchProcess):
            agent = psutil.Process(self.pid)
            return [p for s in agent.children() for p in s.children()]
        return []

    def kill(self) -> None:
        """SIGKILL the agent, as a power cut of its computer would end it."""
        process = self._process
        if process is not None and process.poll() is None:
            process.kill()
            process.wait()

    def stop(self, timeout: float = 30.0) -> int | None:
        """Stop the agent as Ctrl-C does (it ends its components); its exit code."""
        process = self._process
        if process is None:
            return None
        terminate(process, timeout)
        if self._reader is not None:
            self._reader.join(5)
        return process.returncode


def _ip(*args: str) -> None:
    subprocess.run(["ip", *args], check=True, capture_output=True, text=True, timeout=30)


class NetworkNamespace:
    """A network namespace joined to this one by a veth pair: another computer on a
    point-to-point link. ``address`` is this side's, ``inside`` the namespace's."""

    def __init__(self, subnet: int | None = None) -> None:
        tag = uuid.uuid4().hex[:6]
        self.name = f"dura-{tag}"
        self.outer, self.inner = f"dura{tag}o", f"dura{tag}i"
        third = subnet if subnet is not None else int(tag[:2], 16)
        self.address, self.inside = f"10.213.{third}.1", f"10.213.{third}.2"
        self._made = False

    def __enter__(self) -> NetworkNamespace:
        try:
            _ip("netns", "add", self.name)
            self._made = True
            _ip("link", "add", self.outer, "type", "veth", "peer", "name", self.inner)
            _ip("link", "set", self.inner, "netns", self.name)
            _ip("addr", "add", f"{self.address}/30", "dev", self.outer)
            _ip("-n", self.name, "addr", "add", f"{self.inside}/30", "dev", self.inner)
            _ip("-n", self.name, "link", "set", "lo", "up")
            _ip("-n", self.name, "link", "set", self.inner, "up")
            _ip("link", "set", self.outer, "up")
        except BaseException:
            self.__exit__()
            raise
        return self

    def __exit__(self, *exc: object) -> None:
        with contextlib.suppress(subprocess.SubprocessError, OSError):
            _ip("link", "del", self.outer)  # takes its peer along
        if self._made:
            with contextlib.suppress(subprocess.SubprocessError, OSError):
                _ip("netns", "del", self.name)

    def partition(self) -> None:
        """Cut the link (both ends stay up, as a broken cable or switch does)."""
        _ip("link", "set", self.outer, "down")

    def heal(self) -> None:
        _ip("link", "set", self.outer, "up")


def namespaces_usable() -> str:
    """Why network namespaces cannot be used here ("" if they can)."""
    try:
        with NetworkNamespace():
            return ""
    except FileNotFoundError:
        return "no 'ip' command (iproute2)"
    except subprocess.CalledProcessError as e:
        return f"'ip netns' is not allowed here: {(e.stderr or '').strip() or e}"
    except subprocess.SubprocessError as e:
        return f"'ip netns' failed: {e}"
