"""Kill the executive at random moments and check its facts against a replay of its
event log: shared by the property test (``test_recovery.py``) and the benchmark
(``tests/benchmarks/recovery.py``).

The replay knows the use-case domain's effects by heart and knows nothing of plans,
plan ids or run ids: the world is empty until WORLD_SEEDED loads the problem file's,
``dura state set`` and ``unset`` change it, a step is its label (``move_to(dock, lab)``), its run begins with
DISPATCH and ends with the first END, FAIL or CANCEL, START applies its at-start
effects (remembering what each fact was), END its at-end effects, FAIL and CANCEL of a
started run put back what START changed. A run that ends twice, starts without a
dispatch, or names another run than the one begun for its label (when the log names
runs) is a violation. After
a restart, no run of an executive that died may still be open.

Facts and events are read in one read transaction of the SQLite file, so they are
one committed state of the knowledge base, whether the executive runs or was killed.
"""

from __future__ import annotations

import random
import sqlite3
import time
from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from executive.testing.harness import RobotProcess, robot_variant
from tests.conftest import USECASE

Key = tuple[str, tuple[str, ...]]  # a fact: name and arguments

# the use-case domain's effects: (at start, at end), each fact -> its new value
EFFECTS: Mapping[str, Callable[..., tuple[dict[Key, bool], dict[Key, bool]]]] = {
    "move_to": lambda there, to: ({("robot_at", (there,)): False}, {("robot_at", (to,)): True}),
    "take_picture": lambda place: ({}, {("picture_taken", (place,)): True}),
}
STEP_KINDS = ("DISPATCH", "START", "ADOPT", "END", "FAIL", "CANCEL")
USER_KINDS = ("STATE_SET", "STATE_UNSET")
ATOMS = (  # the goals of one fact
    "(robot_at lab)",
    "(robot_at office)",
    "(robot_at dock)",
    "(picture_taken lab)",
    "(picture_taken office)",
)
GOALS = (
    *ATOMS,
    "(and (picture_taken lab) (robot_at office))",
    "(and (picture_taken office) (robot_at dock))",
)
FAST = {  # the use case with short actions: a round sees several steps and replans
    "behaviors": {
        "move_to": {"params": {"duration": 0.8}},
        "take_picture": {"params": {"duration": 0.4}},
    }
}


@dataclass(frozen=True)
class Snapshot:
    """One committed state of the knowledge base: its facts (true atoms) and events."""

    facts: frozenset[Key]
    events: tuple[tuple[int, str, str, dict[str, Any]], ...]


def snapshot(db: Path) -> Snapshot:
    """Read the facts and the step events in one read transaction."""
    import json

    connection = sqlite3.connect(f"file:{db}?mode=ro", uri=True, timeout=10.0)
    try:
        connection.execute("BEGIN")
        facts = frozenset(
            (name, tuple(args.split()))
            for name, args, value in connection.execute("SELECT name, args, value FROM facts")
            if json.loads(value) is True
        )
        kinds = {*STEP_KINDS, *USER_KINDS, "EXECUTIVE_STARTED", "PLAN_START", "WORLD_SEEDED"}
        rows = [
            row
            for row in connection.execute("SELECT id, kind, subject, data FROM events ORDER BY id")
            if row[1] in kinds
        ]
        connection.execute("COMMIT")
    finally:
        connection.close()
    return Snapshot(facts, tuple((i, k, s, json.loads(d)) for i, k, s, d in rows))


def initial_facts(description: Path) -> frozenset[Key]:
    """The true atoms of the robot's problem file: the world its knowledge base starts with."""
    from executive.planning.problem import read_world
    from knowledge.robot import load_robot

    robot = load_robot(description)
    assert robot.problem is not None
    world, _ = read_world(robot.domain, robot.problem)
    return frozenset((f.name, f.args) for f in world.facts if f.value is True)


@dataclass
class _Run:
    id: int
    since: int  # the EXECUTIVE_STARTED the run began under
    before: dict[Key, bool] = field(default_factory=dict)
    started: bool = False


def _atom(text: str) -> Key:
    words = text.strip("() ").split()
    return words[0], tuple(words[1:])


@dataclass
class Replay:
    """The facts the event log says the world has, and what in the log is wrong."""

    facts: set[Key]
    initial: frozenset[Key] = frozenset()  # the world WORLD_SEEDED loads
    violations: list[str] = field(default_factory=list)
    open: dict[str, _Run] = field(default_factory=dict)
    executive: int = 0  # the id of the newest EXECUTIVE_STARTED
    plans: int = 0  # plans started since then

    @classmethod
    def of(
        cls, initial: Iterable[Key], events: Iterable[tuple[int, str, str, dict[str, Any]]]
    ) -> Replay:
        """The replay of ``events``; ``initial`` is the world WORLD_SEEDED loads."""
        replay = cls(set(), frozenset(initial))
        for event in events:
            replay.apply(*event)
        return replay

    def _set(self, changes: Mapping[Key, bool], remember: dict[Key, bool] | None) -> None:
        for key, value in changes.items():
            if remember is not None:
                remember.setdefault(key, key in self.facts)
            if value:
                self.facts.add(key)
            else:
                self.facts.discard(key)

    def apply(self, event_id: int, kind: str, label: str, data: dict[str, Any]) -> None:
        if kind == "EXECUTIVE_STARTED":
            self.executive, self.plans = event_id, 0
            return
        if kind == "PLAN_START":
            self.plans += 1
            return
        if kind == "WORLD_SEEDED":
            self.facts |= self.initial
            return
        if kind in USER_KINDS:
            self._set({_atom(label): kind == "STATE_SET"}, None)
            return
        if kind == "DISPATCH":
            if label in self.open:
                self.violations.append(f"#{event_id}: {label} dispatched while its run runs")
            self.open[label] = _Run(event_id, self.executive)
            return
        run = self.open.get(label)
        if run is None:
            self.violations.append(f"#{event_id}: {kind} {label}, but no run of it is under way")
            return
        if "run" in data and data["run"] != run.id:
            self.violations.append(
                f"#{event_id}: {kind} {label} names run {data.get('run')}, not {run.id}"
            )
        action, _, inside = label[:-1].partition("(")
        args = tuple(a.strip() for a in inside.split(","))
        at_start, at_end = EFFECTS[action](*args)
        if kind == "START":
            if run.started:
                self.violations.append(f"#{event_id}: {label} started twice")
            run.started = True
            self._set(at_start, run.before)
        elif kind == "END":
            del self.open[label]
            self._set(at_end, None)
        elif kind in ("FAIL", "CANCEL"):
            del self.open[label]
            if run.started:
                self._set(run.before, None)

    def running(self) -> list[str]:
        """The steps that had started and not ended."""
        return [label for label, run in self.open.items() if run.started]

    def leftovers(self) -> list[str]:
        """Runs of an executive that died, still open under a newer one."""
        return [
            f"{label} (run {run.id}) of a dead executive is still under way"
            for label, run in self.open.items()
            if run.since < self.executive
        ]


def check(initial: frozenset[Key], db: Path, *, restarted: bool) -> list[str]:
    """What is wrong with the knowledge base's facts now (nothing: ``[]``)."""
    return Checker(initial, db).check(restarted=restarted)


class Checker:
    """Checks a knowledge base again and again, replaying only the events since the
    last check; after a check that found something wrong it goes on from the knowledge
    base's facts, so that each check finds only what went wrong since the last one."""

    def __init__(self, initial: frozenset[Key], db: Path) -> None:
        self.db = db
        self.replay = Replay(set(), initial)
        self.seen = 0  # the newest event replayed

    def check(self, *, restarted: bool) -> list[str]:
        """What is wrong now; ``restarted``: an executive started since the last kill."""
        state = snapshot(self.db)
        replay = self.replay
        replay.violations = []
        for event in state.events:
            if event[0] > self.seen:
                replay.apply(*event)
                self.seen = event[0]
        problems = list(replay.violations)
        if restarted:
            problems += replay.leftovers()
            replay.open = {k: r for k, r in replay.open.items() if r.since == replay.executive}
        if replay.facts != state.facts:
            extra = sorted(state.facts - replay.facts)
            missing = sorted(replay.facts - state.facts)
            problems.append(f"facts differ from the replay: extra {extra}, missing {missing}")
            replay.facts = set(state.facts)
        places = sorted(args[0] for name, args in state.facts if name == "robot_at")
        if len(places) > 1:
            problems.append(f"the robot is in {len(places)} places: {', '.join(places)}")
        return problems


@dataclass
class Round:
    """What one round did, and what was wrong after its kill and after the restart."""

    number: int
    did: str
    left: list[str]  # wrong in what the killed executive left
    running: list[str] = field(default_factory=list)  # steps under way at the kill
    plans: int = 0  # plans the killed executive started (more than one: it replanned)
    recovered: list[str] | None = None  # wrong after the next start (None: not started)
    seconds: float = 0.0

    @property
    def replanned_mid_step(self) -> bool:
        """The kill came while a step ran, after the executive had replanned."""
        return bool(self.running) and self.plans > 1

    @property
    def problems(self) -> list[str]:
        return [
            *(f"after the kill: {p}" for p in self.left),
            *(f"after the restart: {p}" for p in self.recovered or ()),
        ]


class KillRounds:
    """One robot (the fast use case) killed and restarted round after round.

    Each round starts the executive (and checks how it recovered from the last kill),
    gives it a goal (and often a second one a moment later, so that it replans while a
    step runs), waits a random moment, kills it (SIGKILL) and checks the facts the dead
    executive left. The moment: up to ``longest`` seconds after the goal, or a moment
    into the first step that starts after it, or (sometimes) while the executive starts.
    A round with ``replan`` leaves nothing to chance but the moment: it waits for a step
    of the first plan, gives a second goal that is not yet true, and kills a moment into
    the first step of the plan that follows.
    """

    def __init__(self, folder: Path, seed: int) -> None:
        self.random = random.Random(seed)
        description = robot_variant(USECASE, folder / "description", FAST)
        self.robot = RobotProcess(description, folder / "run")
        self.initial = initial_facts(description)
        self.checker = Checker(self.initial, self.robot.kb_path)
        self.rounds: list[Round] = []

    def close(self) -> None:
        self.robot.stop()

    def _restart(self) -> list[str]:
        """Start the executive; what is wrong once it recovered."""
        self.robot.start()
        found = self.checker.check(restarted=True)
        if self.rounds:
            self.rounds[-1].recovered = found
        return found

    def round(self, longest: float = 3.0, *, replan: bool = False) -> Round:
        """One round (see the class docstring)."""
        robot, rng = self.robot, self.random
        began = time.monotonic()
        first = not self.rounds
        mark = self.checker.seen  # the dead executive's last event
        at_start = self._restart()  # the previous round's recovery
        before = at_start if first else []
        did = []
        if not replan and rng.random() < 0.15:  # while it starts: recovering, warming up
            time.sleep(rng.uniform(0.0, 1.0))
            robot.kill()
            did.append(f"killed {time.monotonic() - began:.1f} s after the start")
            return self._killed(began, did, before)
        deadline = time.monotonic() + 60
        while (planning := robot.status().planning) is None or planning.starting:  # warming up
            assert time.monotonic() < deadline, "the planner did not start"
            time.sleep(0.02)
        if rng.random() < 0.3:  # a picture to take again
            for fact in robot.facts("picture_taken"):
                robot.request("state/unset", {"fact": fact})
                did.append(f"unset {fact}")
        open_goals = [g for g in robot.goals() if g.state.is_open]
        if not open_goals:
            goal = rng.choice(GOALS)
            robot.submit_goal(goal)
            did.append(f"goal {goal}")
        last = max((e.id for e in robot.events(limit=1)), default=0)
        moment = rng.uniform(0.0, longest)
        since = time.monotonic()
        if replan or rng.random() < 0.6:  # a second goal while the first plan runs: a replan
            if replan:
                self._wait_for_step(mark)
            else:
                time.sleep(rng.uniform(0.0, moment))
            last = max((e.id for e in robot.events(limit=1)), default=0)
            goal = self._untrue_goal() if replan else rng.choice(GOALS)
            robot.submit_goal(goal)
            did.append(f"goal {goal} after {time.monotonic() - since:.1f} s")
        if replan or rng.random() < 0.5:  # while a step (of the newest plan) runs
            self._wait_for_step(last)
            shortest = FAST["behaviors"]["take_picture"]["params"]["duration"]
            longest_step = FAST["behaviors"]["move_to"]["params"]["duration"]
            time.sleep(rng.uniform(0.0, shortest if replan else longest_step))
        else:
            time.sleep(max(0.0, moment - (time.monotonic() - since)))
        robot.kill()
        did.append(f"killed after {time.monotonic() - since:.1f} s")
        return self._killed(began, did, before)

    def _untrue_goal(self) -> str:
        """A goal that is not true yet and no open goal asks for: one the executive
        must plan for again."""
        facts = set(self.robot.facts())
        asked = {g.expression for g in self.robot.goals() if g.state.is_open}
        return self.random.choice(
            [g for g in ATOMS if g not in facts and g not in asked]
            or [g for g in GOALS if g not in ATOMS]
        )

    def _wait_for_step(self, after: int, timeout: float = 20.0) -> None:
        """Wait (a while at most) until a step starts after the first plan that starts
        after event ``after``."""
        deadline = time.monotonic() + timeout
        plans: list[int] = []
        while time.monotonic() < deadline:
            if not plans:
                plans = [e.id for e in self.robot.events("PLAN_START", limit=5) if e.id > after]
            elif any(e.id > min(plans) for e in self.robot.events("START", limit=5)):
                return
            time.sleep(0.01)

    def _killed(self, began: float, did: list[str], before: list[str]) -> Round:
        """Check what the killed executive left; the round."""
        found = self.checker.check(restarted=False)
        replay = self.checker.replay
        done = Round(
            len(self.rounds) + 1, "; ".join(did), [*before, *found], replay.running(),
            replay.plans, seconds=time.monotonic() - began,
        )  # fmt: skip
        self.rounds.append(done)
        return done

    def final_check(self) -> list[str]:
        """Start once more and check how the executive recovered from the last kill."""
        return self._restart()
