"""Shared fixtures: the use-case robot, free bus endpoints, the dura command."""

from __future__ import annotations

import os
import signal
import socket
import subprocess
import sys
import time
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any

import pytest

from executive.bus.session import Bus
from executive.bus.verb import Verb
from knowledge.errors import NoAnswer

ROOT = Path(__file__).resolve().parent.parent
USECASE = ROOT / "examples" / "usecase" / "robot.yaml"


def free_endpoint() -> str:
    """A loopback TCP endpoint nobody listens on (yet)."""
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return f"tcp/127.0.0.1:{s.getsockname()[1]}"


@pytest.fixture
def endpoint() -> str:
    return free_endpoint()


@pytest.fixture
def usecase_path() -> Path:
    return USECASE


def run_dura(
    *args: str,
    cwd: Path | None = None,
    timeout: float = 120,
    env: Mapping[str, str] | None = None,
) -> subprocess.CompletedProcess[str]:
    """Run the dura command line in a fresh interpreter, as a user would (``env``: the
    environment, e.g. a robot harness's, with its bus credentials)."""
    env = {**(env if env is not None else os.environ), "PYTHONPATH": str(ROOT)}
    return subprocess.run(
        [sys.executable, "-m", "executive.cli", *args],
        capture_output=True,
        text=True,
        cwd=cwd or ROOT,
        env=env,
        timeout=timeout,
        check=False,
    )


@pytest.fixture
def dura() -> Callable[..., subprocess.CompletedProcess[str]]:
    return run_dura


def ended(process: subprocess.Popen[str], timeout: float) -> tuple[str, str]:
    """Wait up to ``timeout`` seconds for ``process`` to end; its stdout and stderr.

    A process that does not end fails the test with the stacks of its threads (from
    ``faulthandler``, which ``PYTHONFAULTHANDLER=1`` in its environment turns on), and is
    killed: it is never left behind to fail the tests after it.
    """
    try:
        return process.communicate(timeout=timeout)
    except subprocess.TimeoutExpired:
        process.send_signal(signal.SIGABRT)  # faulthandler: every thread's stack on stderr
        try:
            _, err = process.communicate(timeout=10)
        except subprocess.TimeoutExpired:
            process.kill()
            _, err = process.communicate()
        raise AssertionError(f"{process.args} did not end within {timeout:g} s:\n{err}") from None


def wait_for(condition: Callable[[], object], timeout: float = 5.0) -> bool:
    """Poll ``condition`` until it holds or ``timeout`` seconds pass; whether it held."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if condition():
            return True
        time.sleep(0.01)
    return bool(condition())


def nobody_answers(bus: Bus, verb: Verb[Any, Any], within: float = 2.0) -> bool:
    """Whether no process serves ``verb`` (nobody answers it within ``within`` seconds).

    The command line asks such a verb again for its whole timeout (30 s: an executive
    that has just started serves its verbs one service after another) before it says so
    in one line; a test that knows nothing is starting asks the bus once."""
    try:
        verb.call(bus, timeout=within)
    except NoAnswer:
        return True
    return False
