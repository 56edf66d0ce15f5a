"""What ``dura demo`` and ``dura run`` show while the robot works: a line for each event
that matters
(as :mod:`executive.bus.event_text` reads it) and each diagnosis, in the order they
happened; each plan the robot executes as a compact timeline when it starts, with the
plan it replaces and why; and, on a terminal only, a last line saying what the robot
does now, so that the demo is never silent.

Events and diagnoses come on two bus subscriptions (two threads), so a rule that fired
on a diagnosis may arrive before it: lines wait ``SETTLE`` seconds and are printed in
the order of their stamps. The process's own warnings come as lines of the same kind
(:class:`WarningLines`).
"""

from __future__ import annotations

import heapq
import io
import itertools
import logging
import queue
import re
import shutil
import sys
import threading
import time
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any, TextIO

from executive.bus.event_kinds import WIDTH
from executive.bus.event_text import describe, diagnosis
from executive.bus.message import Message
from executive.bus.payloads import read_event
from executive.bus.schema import plain
from executive.bus.wording import listed, plural, seconds
from executive.cli.output import bar, table
from knowledge.errors import DuraError
from knowledge.records import Event, Plan

TASK = re.compile(r"\btask (\d+)\b")  # a task named by its number
NAMED_TASK = re.compile(r"\btask (\d+) \w+\(")  # ... and by what it does
SETTLE = 0.3  # seconds a line waits for what happened before it to arrive
TICK = 0.1  # seconds between two looks of the printer
INDENT = " " * 9  # under the time column

# What a person wants to see of the event log; the rest is there with --all-events.
SHOWN = {
    "GOAL_ADDED", "GOAL_ACHIEVED", "GOAL_FAILED", "GOAL_UNREACHABLE", "GOAL_CANCELLED",
    "START", "END", "FAIL", "REPLAN", "CANCEL",
    "COMPONENT_READY", "COMPONENT_EXITED", "COMPONENT_FAILED", "FAULT", "PERMANENT_FAULT",
    "INTEGRITY_GOAL", "CONFIGURATION", "TASK_FAILED", "TASK_PAUSED", "TASK_RESUMED",
    "REPAIR", "TASK_RESTARTED", "RULE_FIRED", "RULE_FAILED", "ROBOT_JOINED", "ROBOT_LOST",
}  # fmt: skip


def replans(events: Sequence[Event]) -> list[int]:
    """The plans (ids) that replaced another while it ran, or that came after a plan
    failed (REPLAN), from the event log in its order: the robot's replans."""
    replacing: set[int] = set()
    failed = False
    found = []
    for event in events:
        kind = event.kind
        if kind == "REPLAN":
            failed = True
        elif kind == "PLAN_STORED" and event.data.get("replaces"):
            replacing.add(_plan_id(event))
        elif kind == "PLAN_START":
            plan = _plan_id(event)
            if plan in replacing or failed:
                found.append(plan)
            failed = False
    return found


def _plan_id(event: Event) -> int:
    return int((event.subject or "plan 0").removeprefix("plan "))


class Timeline:
    """Prints the demo as it goes (see the module docstring) and keeps what it saw.

    Args:
        quiet: print nothing (``--json``); everything is still kept.
        everything: show every event, not only those in ``SHOWN``.
        out: where to print.
        robots: a fleet's robots: each line then names the robot of its plan step (or
            the robot it is about), and each plan is shown by robot.
        robot_of: the robot that carries out an action with these arguments (``None``:
            none of them), for ``robots``.
    """

    def __init__(
        self,
        *,
        quiet: bool,
        everything: bool,
        out: TextIO | None = None,
        robots: Sequence[str] = (),
        robot_of: Callable[[str, Sequence[str]], str | None] = lambda action, args: None,
    ) -> None:
        self.start = time.time()
        self.robots = tuple(robots)
        self.robot_of = robot_of
        self.out = out or sys.stdout
        self.quiet = quiet
        self.everything = everything
        self.live = not quiet and self.out.isatty()
        self.events: list[Event] = []
        self.diagnoses: list[dict[str, Any]] = []
        self.plans: list[dict[str, Any]] = []  # each executed plan, as it started (JSON)
        self.arrived: queue.Queue[Event] = queue.Queue()  # for wait()
        self.activity = "starting the executive"
        self._kb_path: Path | None = None
        self._lock = threading.Lock()
        self._pending: list[tuple[float, int, str, Event | str]] = []  # a heap by stamp
        self._order = itertools.count()
        self._last_diagnosis = ""
        self._states: dict[str, str] = {}  # component → its last COMPONENT_ kind
        self._resumed: set[int] = set()  # COMPONENT_READY events after a pause
        self._planning = ""  # the reason of the newest planning round
        self._why: dict[int, str] = {}  # plan → why it was made (replacing, or after a failure)
        self._replaces: dict[int, int] = {}
        self._failed = ""  # why the last plan failed, until the next one starts
        self._running: dict[str, None] = {}  # steps under way, in order
        self._starting: dict[str, None] = {}  # components coming up
        self._task_names: dict[str, str] = {}  # task number → its step, "move_to(dock, lab)"
        self._task_of: dict[str, str] = {}  # a step → the number of its newest task
        self._introduced: set[str] = set()  # tasks a line has named with their step
        self._drawn = ""  # the live line on the terminal
        self._stop = threading.Event()
        self._printer = threading.Thread(target=self._print_loop, name="demo-timeline")
        self._printer.start()

    def use(self, kb_path: Path) -> None:
        """Read executed plans from this knowledge base (the robot's)."""
        self._kb_path = kb_path

    def close(self) -> None:
        """Print what is still waiting and take the live line away."""
        self._stop.set()
        self._printer.join()
        self._flush(everything=True)
        self._clear()

    # --- what comes in (bus threads, the demo's thread) ---------------------------------

    def say(self, kind: str, text: str) -> None:
        """A line of the demo's own (what it does to the robot), at once."""
        self._push(time.time(), kind, text)

    def doing(self, activity: str) -> None:
        """What the robot does now, for the live line."""
        self.activity = activity

    def on_event(self, message: Message) -> None:
        event = read_event(message.payload)
        if event is None:
            return
        with self._lock:
            self.events.append(event)
            self._follow(event)
        self.arrived.put(event)
        self._push(event.stamp or time.time(), "event", event)

    def on_diagnoses(self, message: Message) -> None:
        payload = message.payload
        shown = diagnosis(payload)
        with self._lock:
            self.diagnoses.append(payload)
            if shown == self._last_diagnosis:
                return
            self._last_diagnosis = shown
        self._push(float(payload.get("stamp") or time.time()), "DIAGNOSIS", shown)

    def wait(self, kind: str, subject: str = "", timeout: float = 60.0) -> Event:
        """The next event of ``kind`` about ``subject``: a component (``lidar``, not
        ``lidar_filter``) or an action (``move_to`` for ``move_to(dock, lab)``)."""
        deadline = time.monotonic() + timeout
        while True:
            left = deadline - time.monotonic()
            if left <= 0:
                raise DuraError(f"demo: no {kind} {subject} within {timeout:g} s")
            try:
                event = self.arrived.get(timeout=left)
            except queue.Empty:
                continue
            about = event.subject
            if event.kind == kind and (
                not subject or about == subject or about.startswith(subject + "(")
            ):
                return event

    def _push(self, stamp: float, kind: str, item: Event | str) -> None:
        with self._lock:
            heapq.heappush(self._pending, (stamp, next(self._order), kind, item))

    def _follow(self, event: Event) -> None:
        """Keep up with what the robot does (in the log's order, under the lock)."""
        kind, subject, data = event.kind, event.subject, event.data
        named = re.fullmatch(r"task (\d+) (.+)", subject) if kind.startswith("TASK_") else None
        if named:
            self._task_names[named.group(1)] = named.group(2)
            if kind == "TASK_STARTED":
                self._task_of[named.group(2)] = named.group(1)
        if kind.startswith("COMPONENT_"):
            if kind == "COMPONENT_READY" and self._states.get(subject) == "COMPONENT_PAUSED":
                self._resumed.add(event.id)
            self._states[subject] = kind
        if kind == "PLANNING":
            self._planning = str(data.get("reason", ""))
            self.activity = f"planning ({self._planning})" if self._planning else "planning"
        elif kind == "PLAN_STORED":
            plan = _plan_id(event)
            self._why[plan] = self._planning
            replaces = data.get("replaces")
            if replaces:
                self._replaces[plan] = int(replaces)
        elif kind == "REPLAN":
            self._failed = str(data.get("reason", "")) or "it failed"
        elif kind == "PLAN_START":  # why this plan, as things stood when it started
            plan = _plan_id(event)
            replaces = self._replaces.get(plan)
            self._why[plan] = self._why.get(plan, "") if replaces else self._failed
            self._failed = ""
        elif kind == "START":
            self._running[subject] = None
        elif kind in ("END", "FAIL", "CANCEL"):
            self._running.pop(subject, None)
        elif kind == "COMPONENT_STARTING":
            self._starting[subject] = None
        elif kind in ("COMPONENT_READY", "COMPONENT_FAILED", "COMPONENT_EXITED"):
            self._starting.pop(subject, None)
        if self._starting:
            self.activity = f"starting {', '.join(self._starting)}"
        elif self._running and kind != "PLANNING":
            self.activity = f"running {', '.join(self._running)}"

    # --- the printer's thread -----------------------------------------------------------

    def _print_loop(self) -> None:
        while not self._stop.wait(TICK):
            self._flush(everything=False)
            self._draw()

    def _flush(self, *, everything: bool) -> None:
        due = time.time() - SETTLE
        while True:
            with self._lock:
                if not self._pending or (not everything and self._pending[0][0] > due):
                    return
                stamp, _, kind, item = heapq.heappop(self._pending)
            self._show(stamp, kind, item)

    def _show(self, stamp: float, kind: str, item: Event | str) -> None:
        if not isinstance(item, Event):
            self._line(stamp, kind, item)
            return
        kind = item.kind
        if kind == "PLAN_START":
            self._plan(stamp, item)
            return
        if not self.everything and (kind not in SHOWN or self._repeated(item)):
            return
        self._line(stamp, kind, self._introducing(item, describe(item)), self.robot(item))

    def robot(self, event: Event) -> str | None:
        """The fleet's robot an event is about: its plan step's, or the robot it names."""
        if event.subject in self.robots:
            return event.subject
        action, args = event.data.get("action"), event.data.get("args")
        if isinstance(action, str) and isinstance(args, list):
            return self.robot_of(action, [str(a) for a in args])
        return None

    def _introducing(self, event: Event, text: str) -> str:
        """A line that names each task with its step the first time (``task 4
        take_picture(lab) succeeded``), and a step's start with its task."""
        with self._lock:
            if event.kind == "START" and event.subject in self._task_of:
                number = self._task_of[event.subject]
                with_task = re.sub(r"(\(plan \d+, step \d+)\)", rf"\1, task {number})", text)
                text = with_task if with_task != text else f"{text} (task {number})"
                self._introduced.add(number)
            self._introduced.update(NAMED_TASK.findall(text))

            def named(found: re.Match[str]) -> str:
                number = found.group(1)
                if number in self._introduced or number not in self._task_names:
                    return found.group(0)
                self._introduced.add(number)
                return f"task {number} {self._task_names[number]}"

            return TASK.sub(named, text)

    def _repeated(self, event: Event) -> bool:
        """A component ready again after a pause (the task's line says it resumed)."""
        with self._lock:
            return event.id in self._resumed

    def _plan(self, stamp: float, event: Event) -> None:
        plan_id = _plan_id(event)
        with self._lock:
            why, replaces = self._why.get(plan_id, ""), self._replaces.get(plan_id)
        stored = self._stored(plan_id)
        data = event.data
        steps = stored.steps if stored is not None else ()
        span = max((s.start + (s.duration or 0.0) for s in steps), default=0.0)
        goals = list(data.get("goals", []))
        engine = stored.engine if stored is not None else ""
        head = f"plan {plan_id} by {engine or '?'} for "
        head += (f"goal {goals[0]}" if len(goals) == 1 else f"goals {listed(goals)}") + ": "
        head += f"{plural(len(steps), 'step')}, {seconds(span)}"
        if replaces:
            head += f"; replaces plan {replaces}" + (f": {why}" if why else "")
        elif why:
            head += f"; the plan before failed: {why}"
        shown = plain(stored) if stored is not None else {"id": plan_id}
        self.plans.append({**shown, "goals": data.get("goals", []), "replaces": replaces,
                           "why": why})  # fmt: skip
        heads: list[str] = ["#", "start", "step", "timeline"]
        if self.robots:  # by robot, each robot's steps in the order they start
            heads.insert(0, "robot")
            steps = tuple(
                sorted(steps, key=lambda s: (self.robot_of(s.action, s.args) or "", s.start))
            )
        rows = io.StringIO()
        table(
            heads,
            [
                [*([self.robot_of(s.action, s.args)] if self.robots else []), s.index,
                 f"{s.start:.1f}", f"{s.action}({', '.join(s.args)})",
                 bar(s.start, s.duration, span)]
                for s in steps
            ],
            rows,
        )  # fmt: skip
        self._line(stamp, "PLAN", head)
        for row in rows.getvalue().splitlines():
            self._write(INDENT + row)

    def _stored(self, plan_id: int) -> Plan | None:
        """The plan as the knowledge base holds it (``None`` if it cannot be read)."""
        if self._kb_path is None:
            return None
        from knowledge.knowledge_base import KnowledgeBase  # only when the reply lacks it

        try:
            with KnowledgeBase(self._kb_path, readonly=True) as kb:
                return kb.plan(plan_id)
        except DuraError:
            return None

    # --- output -------------------------------------------------------------------------

    def _line(self, stamp: float, kind: str, text: str, robot: str | None = None) -> None:
        if self.robots:  # a column for the robot
            width = max(len(r) for r in self.robots)
            text = f"{robot or '':<{width}}  {text}"
        self._write(f"{stamp - self.start:6.1f}s  {kind:<{WIDTH}}  {text}".rstrip())

    def _write(self, text: str) -> None:
        if self.quiet:
            return
        self._clear()
        self.out.write(text + "\n")
        self.out.flush()

    def _draw(self) -> None:
        """The live line, when what it says changed (the clock in whole seconds)."""
        if not self.live:
            return
        now = f"{int(time.time() - self.start):4d}s    now: {self.activity}"
        if self._drawn == now:
            return
        width = shutil.get_terminal_size().columns
        self.out.write("\r" + now[: width - 1] + "\x1b[K")
        self.out.flush()
        self._drawn = now

    def _clear(self) -> None:
        if self._drawn:
            self.out.write("\r\x1b[K")
            self._drawn = ""


class WarningLines(logging.Handler):
    """Log records (warnings and worse) as lines of a timeline, in its format:
    ``  12.3s  WARNING  dura.launcher: 'lidar' ignored SIGTERM ...``."""

    def __init__(self, timeline: Timeline, level: int = logging.WARNING) -> None:
        super().__init__(level)
        self.timeline = timeline

    def emit(self, record: logging.LogRecord) -> None:
        try:
            text = record.getMessage()
        except (TypeError, ValueError):  # a bad format: what it had
            text = str(record.msg)
        self.timeline.say(record.levelname, f"{record.name}: {text}")
