"""Reliability: dura run hard, as a user and an attacker would; every row must read
"nothing lost".

    python -m tests.benchmarks.reliability [--kills N] [--cycles N] [--messages N]
        [--forgeries N] [--goals N] [--requests N] [--only ROW,...]

Rows:
- executive kills: SIGKILLs of the executive at random moments across replans, each
  followed by a restart on the same knowledge base; the facts after recovery must be
  what a replay of the event log says (tests/benchmarks/recovery.py does the rounds);
- component kill cycles: components started and SIGKILLed (some with a program that
  forks grandchildren); afterwards no zombie, no orphan, no growth of the launcher's open
  files or its memory beyond noise;
- malformed bus messages: garbage on every key the executive reads and to every
  declared verb; the executive must keep answering, with no traceback in its log;
- hostile files and arguments: YAML bombs, deep nesting, huge files, unsafe names,
  commands that cannot start, damaged knowledge bases, ASP with syntax errors, numbers
  out of range; each must end in a one-line error with a non-zero exit, within seconds;
- forged identities, hostile ROS 2 goals, dashboard requests without credentials: see
  :mod:`tests.benchmarks.trust`.
"""

from __future__ import annotations

import argparse
import contextlib
import os
import random
import signal
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import psutil
import zenoh

from executive.bus import security
from executive.bus.session import session_config
from executive.bus.states import Lifecycle
from executive.testing.harness import RobotProcess
from tests.benchmarks import trust
from tests.conftest import ROOT, USECASE, free_endpoint, wait_for
from tests.executive.runtime.rig import rig, robot, scripted
from tests.executive.test_hostile_bus import GARBAGE, KEYS, VERBS
from tests.knowledge.test_yamlsource import BOMB, DEEP_BLOCK, DEEP_FLOW


@dataclass
class Row:
    name: str
    passed: int
    tried: int
    detail: str = ""

    @property
    def verdict(self) -> str:
        return "nothing lost" if self.passed == self.tried else "LOST"


# --- executive kills -----------------------------------------------------------------


def executive_kills(rounds: int) -> Row:
    """Kills of the executive across replans, checked against the event log's replay."""
    from tests.benchmarks import recovery

    correct, total, detail = recovery.rounds(rounds)
    return Row("executive kills (facts correct / rounds)", correct, total, detail)


# --- component kill cycles -----------------------------------------------------------


def _open_files() -> int:
    count = 0
    for fd in os.listdir("/proc/self/fd"):
        with contextlib.suppress(OSError):
            target = os.readlink(f"/proc/self/fd/{fd}")
            if not (target.startswith("/dev/shm/") and target.endswith(".zenoh")):
                count += 1
    return count


def _ours(robot_name: str) -> list[psutil.Process]:
    found = []
    for process in psutil.process_iter():
        with contextlib.suppress(psutil.Error):
            if process.environ().get("DURA_ROBOT") == robot_name:
                found.append(process)
    return found


def component_cycles(cycles: int, folder: Path) -> Row:
    """Start components and SIGKILL them; count what is left behind."""
    name = f"reliable{os.getpid()}"
    probe = scripted("probe", "tests.executive.runtime.probe")
    forker = scripted(
        "forker",
        "executive.runtime.translator",
        "process",
        "--",
        "bash",
        "-c",
        "sleep 600 & sleep 600",
    )
    clean = 0
    with rig(robot(probe, forker, name=name), free_endpoint(), folder, grace=1.0) as r:
        for component in ("probe", "forker"):  # warm up: the first start opens what stays
            r.launcher.start(component)
            r.launcher.stop(component)
        files = _open_files()
        memory = psutil.Process().memory_info().rss
        for i in range(cycles):
            component = "forker" if i % 3 == 0 else "probe"
            state = r.launcher.start(component)
            if state.state is not Lifecycle.READY or state.pid is None:
                continue
            tree = [psutil.Process(state.pid), *psutil.Process(state.pid).children(recursive=True)]
            os.kill(state.pid, signal.SIGKILL)
            ended = wait_for(lambda c=component: r.launcher.state(c).state is Lifecycle.EXITED, 10)
            alive = [p for p in tree if _alive(p)]
            clean += ended and not alive and wait_for(lambda: not _zombies(), 5)
        leftovers = [p for p in _ours(name) if _alive(p)]
        grown = _open_files() - files
        rss = (psutil.Process().memory_info().rss - memory) / (1 << 20)
    detail = f"orphans {len(leftovers)}, fds +{grown}, RSS {rss:+.1f} MiB"
    lost = bool(leftovers) or grown > 0 or rss > 50
    return Row("component kill cycles (clean / cycles)", clean - lost, cycles, detail)


def _alive(process: psutil.Process) -> bool:
    try:
        return process.status() != psutil.STATUS_ZOMBIE
    except psutil.NoSuchProcess:
        return False


def _zombies() -> list[psutil.Process]:
    return [
        p
        for p in psutil.Process().children(recursive=True)
        if not _alive(p) and p.pid in {c.pid for c in psutil.Process().children()}
    ]


# --- malformed bus messages ----------------------------------------------------------


def malformed_messages(count: int, folder: Path) -> Row:
    """Garbage on every key the executive reads and to every verb; it must keep going."""
    survived = tried = 0
    rng = random.Random(7)
    with RobotProcess(USECASE, folder / "bus") as robot:
        login = security.find_login(robot.robot.name, security.SERVICE, [robot.folder])
        prefix = f"dura/{robot.robot.name}/"
        with zenoh.open(session_config(connect=(robot.endpoint,), login=login)) as session:
            time.sleep(0.5)
            while tried < count:
                payload = rng.choice(GARBAGE)
                if rng.random() < 0.5:
                    session.put(prefix + rng.choice(KEYS), payload)
                else:
                    verb = rng.choice(VERBS)
                    for _ in session.get(prefix + verb.key, payload=payload, timeout=10.0):
                        pass
                tried += 1
                if tried % 50 == 0 or tried == count:
                    ok = robot.running and robot.status().robot == robot.robot.name
                    survived = tried if ok else survived
        traceback = "Traceback" in robot.log_tail(1_000_000)
    return Row(
        "malformed bus messages (survived / tried)",
        survived if not traceback else 0,
        tried,
        "traceback in the log" if traceback else "",
    )


# --- hostile files and arguments -----------------------------------------------------


def _robot_with(folder: Path, old: str, new: str) -> Path:
    from tests.knowledge.robot_cases import BrokenRobot

    return BrokenRobot("", old, new, "", "").write(folder)


def _damaged_kb(folder: Path, how: str) -> Path:
    from tests.knowledge.test_health import emptied, malformed_page, missing_table, written

    path = written(folder / "usecase.db")
    {"empty": emptied, "table": missing_table, "page": malformed_page}[how](path)
    return path


def hostile_inputs(folder: Path) -> Row:
    """Each hostile input must end in one line on stderr, a non-zero exit, no traceback."""
    cases: list[tuple[str, Callable[[Path], list[str]]]] = [
        ("alias bomb", lambda f: ["validate", str(_write(f / "bomb.yaml", BOMB))]),
        ("deep flow nesting", lambda f: ["validate", str(_write(f / "deep.yaml", DEEP_FLOW))]),
        ("deep block nesting", lambda f: ["validate", str(_write(f / "block.yaml", DEEP_BLOCK))]),
        ("10 MB description", lambda f: ["validate", str(_write(f / "big.yaml", "x: " + "y" * (10 << 20)))]),
        ("rules bomb", lambda f: ["rules", "check", str(_write(f / "rules.yaml", BOMB))]),
        ("robot name a path", lambda f: ["validate", str(_robot_with(f, "robot: usecase", "robot: ../../evil"))]),
        ("component name a path", lambda f: ["validate", str(_robot_with(f, "  cam:\n", "  ../../x:\n"))]),
        ("command one string", lambda f: ["validate", str(_robot_with(f, "    command: [python, -m, components.cam]", "    command: python -m components.cam"))]),
        ("command missing", lambda f: ["validate", str(_robot_with(f, "    command: [python, -m, components.cam]", "    command: [python, -m, components.camra]"))]),
        ("ASP syntax error", lambda f: ["rules", "check", str(_asp_rules(f))]),
        ("empty knowledge base", lambda f: ["run", str(USECASE), "--db", str(_damaged_kb(f, "empty")), "--endpoint", free_endpoint()]),
        ("missing table", lambda f: ["run", str(USECASE), "--db", str(_damaged_kb(f, "table")), "--endpoint", free_endpoint()]),
        ("malformed page", lambda f: ["run", str(USECASE), "--db", str(_damaged_kb(f, "page")), "--endpoint", free_endpoint()]),
        ("huge priority", lambda f: ["goal", "add", "(robot_at dock)", "--priority", "9" * 23]),
        ("NaN deadline", lambda f: ["goal", "add", "(robot_at dock)", "--deadline", "nan"]),
        ("negative timeout", lambda f: ["diagnose", "m.yaml", "--observations", "o.yaml", "--timeout", "-1"]),
        ("id zero", lambda f: ["goal", "show", "0"]),
        ("bag metadata bomb", lambda f: ["replay", str(_bag(f, BOMB)), "--robot", str(USECASE)]),
    ]  # fmt: skip
    clean = 0
    failures = []
    for n, (name, make) in enumerate(cases):
        case_folder = folder / f"case{n}"
        case_folder.mkdir(parents=True)
        argv = make(case_folder)
        try:
            done = subprocess.run(
                [sys.executable, "-m", "executive.cli", *argv],
                capture_output=True,
                text=True,
                timeout=30,
                cwd=case_folder,
                env={**os.environ, "PYTHONPATH": str(ROOT)},
                check=False,
            )
        except subprocess.TimeoutExpired:
            failures.append(f"{name}: hung")
            continue
        lines = [line for line in done.stderr.splitlines() if "warning" not in line]
        if done.returncode != 0 and len(lines) == 1 and "Traceback" not in done.stderr:
            clean += 1
        else:
            failures.append(f"{name}: exit {done.returncode}, {len(lines)} lines")
    return Row("hostile files and arguments (clean errors / tried)", clean, len(cases),
               "; ".join(failures))  # fmt: skip


def _bag(folder: Path, metadata: str) -> Path:
    (folder / "bag").mkdir()
    _write(folder / "bag" / "metadata.yaml", metadata)
    return folder / "bag"


def _write(path: Path, text: str) -> Path:
    path.write_text(text)
    return path


def _asp_rules(folder: Path) -> Path:
    (folder / "bad.lp").write_text('trigger("x") :- ok(.\n')
    return _write(folder / "rules.yaml", "rules: []\nasp: [bad.lp]\n")


# --- the table -------------------------------------------------------------------------


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--kills", type=int, default=30, help="executive kills (200 for the issue)")
    parser.add_argument("--cycles", type=int, default=240, help="component kill cycles")
    parser.add_argument("--messages", type=int, default=1116, help="malformed bus messages")
    parser.add_argument("--forgeries", type=int, default=300, help="forged identities")
    parser.add_argument("--goals", type=int, default=100, help="hostile ROS 2 goals")
    parser.add_argument("--requests", type=int, default=400, help="dashboard requests")
    parser.add_argument("--only", help="the rows to run, by name (kills,cycles,...)")
    args = parser.parse_args()
    only = set(args.only.split(",")) if args.only else None
    os.environ["PYTHONPATH"] = str(ROOT)  # the scripted components import tests.*
    rows = []
    with tempfile.TemporaryDirectory(prefix="dura-reliability-") as folder:
        base = Path(folder)
        for name, run in (
            ("kills", lambda: executive_kills(args.kills)),
            ("cycles", lambda: component_cycles(args.cycles, base / "cycles")),
            ("messages", lambda: malformed_messages(args.messages, base / "messages")),
            ("files", lambda: hostile_inputs(base / "files")),
            ("forgeries", lambda: Row("forged identities (refused / tried)",
                                      *trust.forged_identities(args.forgeries, base / "forged"))),
            ("goals", lambda: Row("hostile ROS 2 goals (survived / tried)",
                                  *trust.hostile_ros2_goals(args.goals, base / "goals"))),
            ("requests", lambda: Row("dashboard requests without credentials (refused / tried)",
                                     *trust.dashboard_without_credentials(args.requests,
                                                                          base / "dashboard"))),
        ):  # fmt: skip
            if only is not None and name not in only:
                continue
            began = time.monotonic()
            print(f"... {name}", file=sys.stderr, flush=True)
            row = run()
            row.detail = (row.detail + f" ({time.monotonic() - began:.0f} s)").strip()
            rows.append(row)
    width = max(len(r.name) for r in rows)
    print(f"{'what':<{width}}  {'result':>11}  verdict       detail")
    for r in rows:
        print(f"{r.name:<{width}}  {r.passed:>5} / {r.tried:<3}  {r.verdict:<12}  {r.detail}")


if __name__ == "__main__":
    main()
