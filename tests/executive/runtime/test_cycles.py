"""Many start/stop/crash cycles leave no zombie, no orphan and no open file behind."""

from __future__ import annotations

import contextlib
import os
import signal
import threading
from pathlib import Path

import psutil
import pytest

from executive.bus.states import Lifecycle
from tests.conftest import wait_for
from tests.executive.runtime.rig import Rig, rig, robot, scripted

CYCLES = 200
WORKERS = 4  # components cycled side by side


def open_files() -> int:
    """Our open files, but for Zenoh's shared-memory segments: Zenoh maps them for its
    links and unmaps them when its own collector runs, which may be in the middle of
    this test for links of an earlier test."""
    ours = 0
    for fd in os.listdir("/proc/self/fd"):
        with contextlib.suppress(OSError):  # the listing's own fd is gone by now
            target = os.readlink(f"/proc/self/fd/{fd}")
            if not (target.startswith("/dev/shm/") and target.endswith(".zenoh")):
                ours += 1
    return ours


def cycle(r: Rig, name: str, i: int) -> None:
    """Start a component and end it in one of four ways."""
    state = r.launcher.start(name)
    assert state.state is Lifecycle.READY, state
    how = i % 4
    if how == 0:
        assert r.launcher.stop(name).state is Lifecycle.STOPPED
    elif how in (1, 2):
        if how == 1:
            assert state.pid is not None
            os.kill(state.pid, signal.SIGKILL)
        else:
            r.launcher.inject_fault(name, "crash")
        assert wait_for(lambda: r.launcher.state(name).state is Lifecycle.EXITED, 10)
    else:
        assert r.launcher.restart(name).state is Lifecycle.READY
        assert r.launcher.stop(name).state is Lifecycle.STOPPED


def orphans(robot_name: str) -> list[psutil.Process]:
    """Processes anywhere that were started for this robot."""
    found = []
    for process in psutil.process_iter():
        with contextlib.suppress(psutil.Error):
            if process.environ().get("DURA_ROBOT") == robot_name:
                found.append(process)
    return found


@pytest.mark.slow
def test_two_hundred_start_stop_crash_cycles_leave_nothing_behind(
    endpoint: str, tmp_path: Path
) -> None:
    name = f"cycles{os.getpid()}"
    probes = [scripted(f"probe{w}", "tests.executive.runtime.probe") for w in range(WORKERS)]
    with rig(robot(*probes, name=name), endpoint, tmp_path, grace=1.0) as r:
        for probe in probes:  # warm up: the first start opens what stays open
            cycle(r, probe.name, 0)
        before = open_files()
        errors: list[BaseException] = []

        def work(component: str) -> None:
            try:
                for i in range(CYCLES // WORKERS):
                    cycle(r, component, i)
            except BaseException as e:
                errors.append(e)

        workers = [threading.Thread(target=work, args=(p.name,)) for p in probes]
        for worker in workers:
            worker.start()
        for worker in workers:
            worker.join()
        assert not errors, errors
        assert r.children() == set()  # no zombies: all reaped
        assert orphans(name) == []
        assert open_files() == before
        restarts = WORKERS * sum(1 for i in range(CYCLES // WORKERS) if i % 4 == 3)
        starts = WORKERS + CYCLES + restarts
        assert wait_for(lambda: len(r.kb.events(kind="COMPONENT_STARTING")) == starts)
