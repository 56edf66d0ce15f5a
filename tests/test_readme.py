"""The README's commands run as it shows them, and print what it shows; so do those of
the documentation's pages its sections moved to (``PAGES``, in the order the README had
them: a reader who follows along runs them in that order).

The runner finds its blocks by itself, so a new section is checked without changing
this file (a new page: add it to ``PAGES``). The rules:

- **Blocks.** Every fenced block marked ``console`` is a session: a line ``$ CMD`` is a
  command (a trailing ``# note`` is the reader's, not the shell's), and the lines up to
  the next command are its shown output. In a block marked ``sh`` (the quick start),
  each ``&&``-joined ``dura`` command runs (the installs and test tools do not: this
  checkout is installed already). Only ``dura`` commands run; others (``ros2 ...``) are
  left to their own tools.
- **Where.** Each block runs in a fresh folder holding links to the repository's
  top-level entries (``examples/usecase/robot.yaml`` is where the README says) and
  ``.dura`` of one running robot, the use case, shared by the whole module
  (:class:`RobotProcess` with its knowledge base in ``.dura``, as ``dura run`` keeps
  it): commands find the running executive, its credentials and its knowledge base as
  they would in the folder where ``dura run`` runs. ``dura run`` of the use case is that
  robot (its first line is compared with the one shown); a block that runs another
  robot fails, saying so. Blocks run in the README's order on that one robot, as a
  reader who follows along would run them, except that a block whose output numbers
  goals or tasks from 1 (``goal 1: ...``) gets a fresh robot when the shared one has
  numbered some already (a block may count as if the robot had just started), and the
  blocks after it share that one. Before a block, the robot finishes what earlier
  blocks gave it (no open goal, no task). Files a block
  names that the README shows elsewhere or that come from the robot (a robot
  description with a typo, the diagnosis model, a bag) are made by ``SETUP``, keyed by
  the block's first command; ``CHECKS`` adds checks to a command (the demo's counts).
- **Exit.** A command with no shown output must exit 0; one with shown output must
  print it, whatever its exit code (the README may show an error). A command runs as
  written, so it names real files and ids (placeholders such as ``ROBOT.yaml`` belong
  in the prose and the command table). Commands that run until Ctrl-C (``--follow``,
  ``dashboard``, ``record``) run ``FOLLOW`` seconds and are interrupted, as a person
  would; their output is not compared.
- **Output** (stdout, else stderr, else both) is compared line by line after these
  rules, applied to both sides: a shown ``...`` stands for any lines (or none), and
  the output may go on after the last line shown (the README may stop early); runs of
  spaces are one (column widths follow the content); what depends on the moment or
  the machine is not compared: clock times, pids (``pid 4242``, a ``PID`` column),
  loopback ports, the computer's name (a ``HOST`` column), durations and ages
  (``0.09 s``, ``1.9 ms``, ``0.3s``), rates
  (``9.998 Hz``), signed offsets (``+4.2``) and timeline bars (``|██  |``); a shown
  JSON line means the printed JSON holds at least its keys with their values.
- **A live robot moves on.** A command that changes nothing (``show``, ``list``,
  ``get``, ``status``, ``observe``, ``logs``) is asked again for up to ``SETTLE``
  seconds until its output matches: a person reads the robot a moment later than a
  script does. Commands that change something run once.
"""

from __future__ import annotations

import json
import os
import re
import shlex
import signal
import subprocess
import sys
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from pathlib import Path

import pytest

from executive.bus.api import planning
from executive.testing.harness import RobotProcess, robot_variant
from tests.conftest import ROOT, USECASE

pytestmark = pytest.mark.slow

README = ROOT / "README.md"
# The README, then the pages its sections moved to, in the order the README had them.
PAGES = [README, *(ROOT / "docs" / page for page in (
    "explanation/architecture.md",
    "how-to/robot-description.md",
    "explanation/knowledge-base.md",
    "explanation/bus.md",
    "how-to/security.md",
    "how-to/run.md",
    "how-to/several-computers.md",
    "how-to/components.md",
    "how-to/observers.md",
    "how-to/diagnosis-and-repair.md",
    "how-to/ros2.md",
    "how-to/bags.md",
    "explanation/scheduling.md",
    "explanation/planning.md",
    "how-to/goals.md",
    "how-to/dashboard.md",
    "how-to/testing.md",
    "reference/cli.md",
    "development.md",
    "how-to/fleets.md",
))]  # fmt: skip
FOLLOW = 2.0  # seconds a command that runs until Ctrl-C runs
SETTLE = 60.0  # seconds a command that changes nothing is asked again until it matches
IDLE = 90.0  # seconds the robot may take to finish what earlier blocks gave it
TIMEOUT = 240.0  # seconds any one command may take (the demo is the longest)
READ_ONLY = {"show", "list", "get", "status", "observe", "logs", "--dry-run"}


@dataclass
class Command:
    line: int  # in its page
    text: str  # as written, without the note
    argv: list[str]
    shown: list[str] = field(default_factory=list)  # the output the README shows

    @property
    def endless(self) -> bool:
        """It runs until Ctrl-C."""
        return "--follow" in self.argv or self.argv[1:2] in (["dashboard"], ["record"])

    @property
    def read_only(self) -> bool:
        return bool(READ_ONLY & set(self.argv[1:3])) and "--svg" not in self.argv


@dataclass
class Block:
    line: int
    commands: list[Command]
    page: str = "README.md"  # where it is, from the repository's root

    @property
    def name(self) -> str:
        first = self.commands[0].text if self.commands else "-"
        return f"{self.page}:{self.line} {first[:50]}"


def blocks(text: str, page: str = "README.md") -> Iterator[Block]:
    """A page's blocks that show commands, in order."""
    lines = text.splitlines()
    i = 0
    while i < len(lines):
        fence = re.match(r"^```(\w*)\s*$", lines[i])
        if not fence:
            i += 1
            continue
        kind, start = fence.group(1), i + 1
        end = next(j for j in range(start, len(lines)) if lines[j].startswith("```"))
        body = lines[start:end]
        if kind == "console":
            yield Block(start, _session(body, start), page)
        elif kind == "sh":
            yield Block(start, _shell(body, start), page)
        i = end + 1


def _session(body: list[str], first: int) -> list[Command]:
    commands: list[Command] = []
    for n, line in enumerate(body, first + 1):
        if line.startswith("$ "):
            argv = shlex.split(line[2:], comments=True)
            text = shlex.join(argv)
            commands.append(Command(n, text, argv))
        elif commands:
            commands[-1].shown.append(line)
    return commands


def _shell(body: list[str], first: int) -> list[Command]:
    commands = []
    for n, line in enumerate(body, first + 1):
        for part in line.split("&&"):
            argv = shlex.split(part, comments=True)
            if argv and Path(argv[0]).name == "dura":
                argv[0] = "dura"
                commands.append(Command(n, shlex.join(argv), argv))
    return commands


# --- comparing what is printed with what is shown ---------------------------------------

MOMENTARY = [
    (re.compile(r"\b\d{1,2}:\d\d:\d\d(\.\d+)?\b"), "<clock>"),
    (re.compile(r"\bpid \d+"), "pid <n>"),
    (re.compile(r"tcp/[\d.]+:\d+"), "tcp/<endpoint>"),
    (re.compile(r"\|[█ ]+\|"), "<bar>"),
    (re.compile(r"(?<![\w.])\d+(\.\d+)? ?Hz\b"), "<rate>"),
    (re.compile(r"(?<![\w.])\d+(\.\d+)? ?(ms|s)\b"), "<time>"),
    (re.compile(r"(?<![\w.])[+-]\d+(\.\d+)?\b"), "<offset>"),
]
NOTE = re.compile(r"\s{2,}#\s.*$")


def normalised(lines: list[str]) -> list[str]:
    """Lines as compared (see the module docstring)."""
    out, pid_column, host_column = [], None, None
    for raw in lines:
        cells = re.split(r" {2,}", raw.strip())
        if cells and all(re.fullmatch(r"[A-Z#][A-Z_ ]*", c) for c in cells) and len(cells) > 1:
            pid_column = cells.index("PID") if "PID" in cells else None
            host_column = cells.index("HOST") if "HOST" in cells else None
        elif not raw.strip():
            pid_column = host_column = None
        else:
            if pid_column is not None and len(cells) > pid_column and cells[pid_column].isdigit():
                cells[pid_column] = "<pid>"
            if host_column is not None and len(cells) > host_column:
                cells[host_column] = "<host>"
        line = " ".join(cells)
        for pattern, placeholder in MOMENTARY:
            line = pattern.sub(placeholder, line)
        out.append(" ".join(line.split()))
    return out


def matches(printed: list[str], shown: list[str]) -> bool:
    """Whether printed lines begin as the shown ones, a ``...`` standing for any lines."""
    got, want = normalised(printed), normalised([NOTE.sub("", s) for s in shown])
    while got and not got[-1]:
        got.pop()
    while want and not want[-1]:
        want.pop()

    def fit(i: int, j: int) -> bool:
        if j == len(want):
            return True  # what follows the last shown line is not shown
        if want[j] == "...":
            return any(fit(k, j + 1) for k in range(i, len(got) + 1))
        return i < len(got) and got[i] == want[j] and fit(i + 1, j + 1)

    return fit(0, 0)


def json_fits(printed: str, shown: list[str]) -> bool | None:
    """For a shown JSON line: whether the printed JSON holds it (``None``: not JSON)."""
    lines = [NOTE.sub("", s).strip() for s in shown if s.strip()]
    if len(lines) != 1 or lines[0][:1] not in "{[":
        return None
    try:
        want = json.loads(lines[0])
        got = json.loads(printed)
    except json.JSONDecodeError:
        return False
    if isinstance(want, dict):
        return isinstance(got, dict) and all(got.get(k) == v for k, v in want.items())
    return bool(got == want)


def fits(done: subprocess.CompletedProcess[str], shown: list[str]) -> bool:
    as_json = json_fits(done.stdout, shown)
    if as_json is not None:
        return as_json
    out, err = done.stdout.splitlines(), done.stderr.splitlines()
    return any(matches(printed, shown) for printed in (out, err, out + err))


# --- files the README shows elsewhere ---------------------------------------------------


def broken_robot(folder: Path) -> None:
    """The use case with a typo in lidar_filter's requires, line for line."""
    text = USECASE.read_text(encoding="utf-8")
    text = text.replace("../../domains", str(ROOT / "domains"))
    (folder / "robot.yaml").write_text(
        text.replace("requires: [laser_scan]", "requires: [laser_scna]", 1), encoding="utf-8"
    )
    for entry in USECASE.parent.iterdir():
        if entry.name != "robot.yaml" and not (folder / entry.name).exists():
            (folder / entry.name).symlink_to(entry)


def diagnosis_files(folder: Path) -> None:
    """model.yaml and obs.yaml from the README's two-column block (``# MODEL.yaml``): the
    right column starts after the first gap of three spaces or more on a line."""
    lines = [line for page in PAGES for line in page.read_text(encoding="utf-8").splitlines()]
    start = next(i for i, line in enumerate(lines) if line.startswith("# MODEL.yaml"))
    end = next(i for i in range(start, len(lines)) if lines[i].startswith("```"))
    model, observations = [], []
    for line in lines[start + 1 : end]:
        found = re.match(r"^(.*?\S) {3,}(\S.*)$", line)
        model.append(found.group(1) if found else line.rstrip())
        observations.append(found.group(2) if found else "")
    (folder / "model.yaml").write_text("\n".join(model) + "\n", encoding="utf-8")
    (folder / "obs.yaml").write_text("\n".join(observations) + "\n", encoding="utf-8")


def lidar_bag(folder: Path) -> None:
    """``lidar_run``: a 10 Hz scan that hiccups for 0.7 s at 10 s and stops for 2 s at
    20 s (29.9 s, 273 messages), and the use case as ``robot.yaml``."""
    from tests.executive.bags.recorded import T0, write_scan_bag

    times = [T0 * 10**9 + k * 10**8 for k in range(300) if not (100 <= k < 107 or 200 <= k < 220)]
    write_scan_bag(folder / "lidar_run", times=times)
    robot_variant(USECASE, folder, {})


def flawed_domain(folder: Path) -> None:
    """domain.pddl and problem.pddl with what ``dura domain check`` warns about."""
    from tests.executive.planning.planning_cases import FLAWED_DOMAIN, FLAWED_PROBLEM

    (folder / "domain.pddl").write_text(FLAWED_DOMAIN, encoding="utf-8")
    (folder / "problem.pddl").write_text(FLAWED_PROBLEM, encoding="utf-8")


def broken_warehouse(folder: Path) -> None:
    """The warehouse domain with a misspelt predicate (warehouse.pddl) and with a ')'
    missing (unclosed.pddl), and its problem (hall.pddl)."""
    from tests.executive.planning.planning_cases import WAREHOUSE_DOMAIN, WAREHOUSE_PROBLEM

    misspelt = WAREHOUSE_DOMAIN.replace("(at start (free ?v))", "(at start (fre ?v))")
    unclosed = WAREHOUSE_DOMAIN.replace("(road ?from ?to)))", "(road ?from ?to))")
    (folder / "warehouse.pddl").write_text(misspelt, encoding="utf-8")
    (folder / "unclosed.pddl").write_text(unclosed, encoding="utf-8")
    (folder / "hall.pddl").write_text(WAREHOUSE_PROBLEM, encoding="utf-8")


SETUP: dict[str, Callable[[Path], None]] = {
    "dura domain check domain.pddl problem.pddl": flawed_domain,
    "dura plan --offline warehouse.pddl hall.pddl": broken_warehouse,
    "dura validate robot.yaml": broken_robot,
    "dura diagnose model.yaml --observations obs.yaml": diagnosis_files,
    "ros2 bag record /scan -o lidar_run": lidar_bag,
}


def demo_is_consistent(done: subprocess.CompletedProcess[str]) -> None:
    """``dura demo``: every plan it executed shown, replans and goals counted right."""
    lines = done.stdout.splitlines()
    plans = [line for line in lines if re.match(r"\s*[\d.]+s  PLAN\s", line)]
    summary = next(line for line in lines if " started" in line and " replan" in line)
    count = re.search(r"(\d+) plans? started(?: \(\d+ replaced before its first step\))?, "
                      r"(\d+) replans?", summary)  # fmt: skip
    assert count is not None, summary
    assert int(count.group(1)) == len(plans) >= 1, summary
    replaced = [p for p in plans if "replaces plan" in p or "the plan before failed" in p]
    assert int(count.group(2)) == len(replaced), summary
    assert re.fullmatch(r"(\d+) of \1 goals achieved", lines[-1]), lines[-1]


CHECKS: dict[str, Callable[[subprocess.CompletedProcess[str]], None]] = {
    "dura demo": demo_is_consistent,
    "dura demo --fleet": demo_is_consistent,
}


# --- running them ------------------------------------------------------------------------


def use_case(folder: Path) -> RobotProcess:
    """The use case's executive as ``dura run`` runs it in ``folder`` (not started)."""
    robot = RobotProcess(USECASE, folder)
    robot.kb_path = folder / ".dura" / f"{robot.robot.name}.db"  # where dura run keeps it
    robot.kb_path.parent.mkdir(parents=True, exist_ok=True)
    return robot


class Robots:
    """The robot the blocks share: the use case, until a block needs a fresh one, which
    the blocks after it share then."""

    def __init__(self, folder: Path) -> None:
        self.folder = folder
        self.current = use_case(folder / "robot-1")
        self.current.start()

    def fresh(self) -> RobotProcess:
        self.current.stop()
        self.current = use_case(self.folder / f"robot-{len(list(self.folder.iterdir())) + 1}")
        self.current.start()
        return self.current


@pytest.fixture(scope="module")
def robots(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Robots]:
    shared = Robots(tmp_path_factory.mktemp("readme-robots"))
    try:
        yield shared
    finally:
        shared.current.stop()


FROM_ONE = re.compile(r"^(goal|task) 1\b")


def counts_from_one(block: Block) -> bool:
    """Whether a block's output numbers goals or tasks from 1 (a fresh robot's)."""
    return any(FROM_ONE.match(line) for c in block.commands for line in c.shown)


def numbered(robot: RobotProcess) -> bool:
    """Whether the robot has goals or tasks already."""
    status = planning.STATUS.call(robot.bus)
    return bool(status.goals or status.tasks)


def workspace(folder: Path, robot: RobotProcess) -> Path:
    folder.mkdir(parents=True)
    for entry in ROOT.iterdir():
        if not entry.name.startswith(".") and entry.name != "README.md":
            (folder / entry.name).symlink_to(entry)
    (folder / ".dura").symlink_to(robot.folder / ".dura")
    return folder


def run(command: Command, folder: Path) -> subprocess.CompletedProcess[str]:
    argv = [sys.executable, "-m", "executive.cli", *command.argv[1:]]
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    if not command.endless:
        return subprocess.run(argv, cwd=folder, env=env, capture_output=True, text=True,
                              timeout=TIMEOUT, check=False)  # fmt: skip
    with subprocess.Popen(argv, cwd=folder, env=env, stdout=subprocess.PIPE,
                          stderr=subprocess.PIPE, text=True) as process:  # fmt: skip
        time.sleep(FOLLOW)
        process.send_signal(signal.SIGINT)
        out, err = process.communicate(timeout=30)
    return subprocess.CompletedProcess(argv, 0, out, err)


def wait_until_idle(robot: RobotProcess) -> None:
    deadline = time.monotonic() + IDLE
    while time.monotonic() < deadline:
        status = planning.STATUS.call(robot.bus)
        goals = [g for g in status.goals if g.state.is_open]
        assert not isinstance(status.tasks, planning.Unanswered), status.tasks
        tasks = [t for t in status.tasks or [] if t.state not in _ENDED]
        if not goals and not tasks:
            return
        time.sleep(0.5)
    raise AssertionError(f"the robot is still busy after {IDLE:g} s: {robot.log_tail()}")


_ENDED = ("succeeded", "failed", "cancelled")
BLOCKS = [
    b
    for page in PAGES
    for b in blocks(page.read_text(encoding="utf-8"), page.relative_to(ROOT).as_posix())
    if b.commands
]


@pytest.mark.parametrize("block", BLOCKS, ids=[b.name for b in BLOCKS])
def test_the_readme_block_runs_as_shown(block: Block, robots: Robots, tmp_path: Path) -> None:
    if not any(c.argv[0] == "dura" for c in block.commands):
        pytest.skip("no dura command: the README leaves it to its own tool")
    robot = robots.current
    wait_until_idle(robot)
    if counts_from_one(block) and numbered(robot):
        robot = robots.fresh()
    run_block(block, robot, tmp_path)


def run_block(block: Block, robot: RobotProcess, tmp_path: Path) -> None:
    folder = workspace(tmp_path / "work", robot)
    setup = SETUP.get(block.commands[0].text)
    if setup is not None:
        setup(folder)
    for command in block.commands:
        if command.argv[0] != "dura":
            continue
        where = f"{block.page}:{command.line}: $ {command.text}"
        if command.argv[1] == "run":
            ran = ROOT / command.argv[2] if len(command.argv) > 2 else None
            assert ran is not None and ran.resolve() == USECASE.resolve(), (
                f"{where}: the README runner runs one robot, {USECASE.relative_to(ROOT)}; "
                "teach tests/test_readme.py a second robot to run this one"
            )
            first = robot.output.read_text(encoding="utf-8").splitlines()[:1]
            assert not command.shown or matches(first, command.shown), f"{where}\n{first}"
            continue
        compared = bool(command.shown) and not command.endless
        deadline = time.monotonic() + (SETTLE if command.read_only and compared else 0)
        while True:
            done = run(command, folder)
            if not compared or fits(done, command.shown) or time.monotonic() > deadline:
                break
            time.sleep(0.5)
        printed = f"exit {done.returncode}\n--- stdout\n{done.stdout}--- stderr\n{done.stderr}"
        if compared:
            assert fits(done, command.shown), (
                f"{where}\nshown:\n" + "\n".join(command.shown) + f"\nprinted: {printed}"
            )
        elif not command.endless and not command.shown:
            assert done.returncode == 0, f"{where}\n{printed}"
        check = CHECKS.get(command.text)
        if check is not None:
            check(done)


def test_the_rules_of_comparison_hold() -> None:
    shown = ["ID  TASK  PID   SINCE     TIMELINE", "1   a     4250  10:02:17  |██  |", "..."]
    printed = ["ID  TASK  PID  SINCE     TIMELINE", "1   a     17   11:12:13  |   █|", "2", "3"]
    assert matches(printed, shown)
    assert matches(printed, shown[:2])  # the README may stop early
    assert not matches(printed[1:], shown)
    assert not matches(["1   b     17   11:12:13  |   █|"], shown[1:2])
    assert matches(["took 0.31 s, 9.98 Hz, -0.8"], ["took 0.3s, 10 Hz, +4.2  # a note"])
    assert matches(
        ["NAME   HOST  STATE", "lidar  vm    ready"], ["NAME  HOST  STATE", "lidar  main  ready"]
    )
    assert not matches(
        ["NAME   HOST  STATE", "lidar  vm    ready"], ["NAME  HOST  STATE", "lidar  main  stopped"]
    )
    assert json_fits('{\n  "status": "OK",\n  "more": 1\n}', ['{"status": "OK"}  # indented'])
