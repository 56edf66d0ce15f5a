"""The C heap of a long-running process: arenas capped, free pages given back, no cache
of freed blocks per thread (glibc).

Each check runs in a Python process of its own: an arena cap holds for a whole process,
only threads that have no arena yet heed it, and glibc reads its tunables when a program
starts."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import textwrap
from pathlib import Path

import psutil
import pytest

from executive.runtime.native_heap import _glibc
from executive.testing.harness import RobotProcess
from tests.conftest import USECASE

pytestmark = pytest.mark.skipif(_glibc() is None, reason="glibc's malloc only")

# threads that each take a block from malloc while all of them are alive, then the
# number of heaps glibc's malloc_info reports (the main arena and one per other arena)
ARENAS = """
import ctypes, os, tempfile, threading
from executive.runtime.native_heap import limit_arenas
capped = limit_arenas() if CAP else False
libc = ctypes.CDLL("libc.so.6")
libc.malloc.restype = ctypes.c_void_p
libc.fopen.restype = ctypes.c_void_p
libc.fopen.argtypes = [ctypes.c_char_p, ctypes.c_char_p]
libc.malloc_info.argtypes = [ctypes.c_int, ctypes.c_void_p]
libc.fclose.argtypes = [ctypes.c_void_p]
together = threading.Barrier(8)
def take():
    libc.malloc(4000)
    together.wait()
threads = [threading.Thread(target=take) for _ in range(8)]
for t in threads: t.start()
for t in threads: t.join()
path = tempfile.mktemp()
f = libc.fopen(path.encode(), b"w"); libc.malloc_info(0, f); libc.fclose(f)
heaps = open(path).read().count("<heap nr="); os.unlink(path)
print(json.dumps({"capped": capped, "heaps": heaps}))
"""

# many small blocks, most of them freed, every 64th kept: the free chunks lie between
# blocks in use, where free() itself never gives pages back
TRIM = """
import ctypes, time
from executive.runtime.native_heap import HeapTrimmer, trim
libc = ctypes.CDLL("libc.so.6")
libc.malloc.restype = ctypes.c_void_p
libc.free.argtypes = [ctypes.c_void_p]
def rss():
    for line in open("/proc/self/status"):
        if line.startswith("VmRSS"):
            return int(line.split()[1])
blocks = [libc.malloc(1000) for _ in range(60000)]
for i, b in enumerate(blocks):
    ctypes.memset(b, 1, 1000)
for i, b in enumerate(blocks):
    if i % 64:
        libc.free(b)
before = rss()
if MODE == "now":
    trimmed = trim()
else:
    with HeapTrimmer(every=0.05):
        deadline = time.monotonic() + 30
        while rss() > before - 20000 and time.monotonic() < deadline:
            time.sleep(0.05)
    trimmed = None
print(json.dumps({"before": before, "after": rss(), "trimmed": trimmed}))
"""


def _run(program: str, **names: object) -> dict[str, object]:
    preamble = "import json\n" + "".join(f"{k} = {v!r}\n" for k, v in names.items())
    env = {k: v for k, v in os.environ.items() if k != "MALLOC_ARENA_MAX"}
    done = subprocess.run([sys.executable, "-c", preamble + textwrap.dedent(program)],
                          capture_output=True, text=True, env=env, timeout=60, check=True)  # fmt: skip
    result: dict[str, object] = json.loads(done.stdout)
    return result


def test_the_arenas_are_capped() -> None:
    free = _run(ARENAS, CAP=False)
    capped = _run(ARENAS, CAP=True)
    assert capped["capped"] is True
    assert capped["heaps"] == 2  # the main arena and one for all the threads
    assert free["heaps"] > 2  # without the cap, threads get arenas of their own


def test_the_variable_wins() -> None:
    program = "from executive.runtime.native_heap import limit_arenas; print(limit_arenas())"
    env = {**os.environ, "MALLOC_ARENA_MAX": "4"}
    done = subprocess.run([sys.executable, "-c", program], capture_output=True, text=True,
                          env=env, timeout=60, check=True)  # fmt: skip
    assert done.stdout.strip() == "False"


def test_a_trim_gives_free_pages_back() -> None:
    result = _run(TRIM, MODE="now")
    assert result["trimmed"] is True
    # about 58 MB were freed between kept blocks; most of it goes back
    assert int(result["after"]) < int(result["before"]) - 20000  # type: ignore[call-overload]


def test_the_trimmer_trims_on_its_own() -> None:
    result = _run(TRIM, MODE="thread")
    assert int(result["after"]) < int(result["before"]) - 20000  # type: ignore[call-overload]


# the program started again with the thread caches off, as `dura run` is: its pid at
# each start (stderr), the variable it has and gives what it starts, and by how many
# bytes malloc's count in use falls when seven blocks of 1000 bytes are freed (a thread
# cache keeps them, and glibc counts them in use). glibc cuts GLIBC_TUNABLES short at its
# first tunable in the environment a program sees (its tunables all hold, though).
RESTART = """
import ctypes, os, subprocess, sys
print("started", os.getpid(), file=sys.stderr, flush=True)
from executive.runtime.native_heap import restart_without_thread_caches
restart_without_thread_caches()
class Info(ctypes.Structure):
    _fields_ = [(name, ctypes.c_size_t) for name in ("arena", "ordblks", "smblks", "hblks",
                "hblkhd", "usmblks", "fsmblks", "uordblks", "fordblks", "keepcost")]
libc = ctypes.CDLL("libc.so.6")
libc.mallinfo2.restype = Info
libc.malloc.restype = ctypes.c_void_p
libc.free.argtypes = [ctypes.c_void_p]
blocks = [libc.malloc(1000) for _ in range(7)]
before = libc.mallinfo2().uordblks
for b in blocks:
    libc.free(b)
child = subprocess.run([sys.executable, "-c", "import os; print(os.environ.get('GLIBC_TUNABLES'))"],
                       capture_output=True, text=True, check=True).stdout.strip()
print(json.dumps({"pid": os.getpid(), "later": os.environ.get("GLIBC_TUNABLES"), "child": child,
                  "held": before - libc.mallinfo2().uordblks}))
"""


def _restarted(tunables: str | None) -> tuple[dict[str, object], str]:
    env = {k: v for k, v in os.environ.items() if k != "GLIBC_TUNABLES"}
    if tunables is not None:
        env["GLIBC_TUNABLES"] = tunables
    done = subprocess.run([sys.executable, "-c", "import json\n" + RESTART],
                          capture_output=True, text=True, env=env, timeout=60, check=True)  # fmt: skip
    result: dict[str, object] = json.loads(done.stdout)
    return result, done.stderr


def test_the_program_starts_again_in_its_process_with_the_thread_caches_off() -> None:
    result, said = _restarted(None)
    assert said.split() == ["started", str(result["pid"])] * 2  # twice, in the same process
    assert result["later"] is None and result["child"] == "None"  # what it starts: as before
    assert int(result["held"]) >= 7 * 1000  # type: ignore[call-overload]  # free at once


def test_the_users_tunables_are_kept_and_their_thread_caches_win() -> None:
    others, said = _restarted("glibc.malloc.arena_max=4")
    assert said.split() == ["started", str(others["pid"])] * 2
    assert others["later"] == others["child"] == "glibc.malloc.arena_max=4"
    assert int(others["held"]) >= 7 * 1000  # type: ignore[call-overload]  # both tunables hold
    chosen, said = _restarted("glibc.malloc.tcache_count=7")
    assert said.split() == ["started", str(chosen["pid"])]  # not started again
    assert chosen["later"] == chosen["child"] == "glibc.malloc.tcache_count=7"
    assert int(chosen["held"]) < 1000  # type: ignore[call-overload]  # kept by the cache


@pytest.mark.slow
def test_dura_run_runs_without_thread_caches_and_its_components_as_they_were(
    tmp_path: Path,
) -> None:
    os.environ.pop("GLIBC_TUNABLES", None)
    with RobotProcess(USECASE, tmp_path) as robot:
        state = robot.request("component/start", {"name": "lidar"})
        assert state["state"] == "ready", state
        executive = psutil.Process(robot.pid)  # the process the harness started
        component = psutil.Process(int(state["pid"]))
        assert executive.environ().get("GLIBC_TUNABLES") == "glibc.malloc.tcache_count=0"
        assert component in executive.children(recursive=True)
        assert "GLIBC_TUNABLES" not in component.environ()
