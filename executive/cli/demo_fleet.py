"""``dura demo --fleet``: a fleet of transport robots end to end (``examples/fleet``).

It starts the executives of the example's three transport robots (each with its
simulated components, on a clock twice as fast as the wall clock) and the fleet's high
level (``dura fleet run``) in a temporary folder, asks for three deliveries, and shows
each plan the fleet executes by robot and each event with the robot it is about
(:mod:`executive.cli.demo_timeline`). When the first robot starts picking up a parcel,
its executive is killed (SIGKILL); the fleet loses it, plans again without it, and the
others deliver every parcel. It ends with a summary (the goals and who delivered each,
what each robot did on one time axis, the counts): exit 0 if every parcel was
delivered, or 1 with the reason.
"""

from __future__ import annotations

import argparse
import contextlib
import sys
import tempfile
import time
from collections.abc import Callable, Iterable, Mapping, Sequence
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from executive.bus.keys import EVENTS
from executive.bus.schema import plain
from executive.bus.wording import listed, plural, seconds
from executive.cli.demo_timeline import Timeline, replans
from executive.cli.output import BAR, print_json, section, table
from executive.testing.fleet import FleetProcess, fleet_variant
from executive.testing.harness import RobotProcess
from knowledge.errors import DuraError
from knowledge.records import Event, Goal, GoalState

EXAMPLE = Path(__file__).resolve().parents[2] / "examples" / "fleet"
ROBOTS = ("r1", "r2", "r3")
DELIVERIES = (("parcel1", "lab"), ("parcel2", "office"), ("parcel3", "lab"))
SCALE = 2.0  # robot time runs twice as fast as the wall clock: a drive takes 2.5 s
TIMEOUT = 180.0  # seconds for the deliveries once the robot is killed
STEP_ENDS = ("END", "FAIL", "CANCEL")

RobotOf = Callable[[str, Sequence[str]], str | None]


def run(args: argparse.Namespace) -> int:
    if not (EXAMPLE / "fleet.yaml").is_file():
        raise DuraError(f"the example fleet is missing: {EXAMPLE} (run from a dura checkout)")
    if args.keep is not None:
        args.keep.mkdir(parents=True, exist_ok=True)
        return _demo(args, args.keep.resolve())
    with tempfile.TemporaryDirectory(prefix="dura-demo-fleet-") as folder:
        return _demo(args, Path(folder))


@dataclass
class Outcome:
    """What the demo saw: the goals at the end, the fleet's event log, the robot it
    killed."""

    goals: list[Goal]
    events: list[Event]
    killed: str


def _demo(args: argparse.Namespace, folder: Path) -> int:
    robot_of = robot_finder(EXAMPLE / "fleet.yaml")
    timeline = Timeline(
        quiet=args.json, everything=args.all_events, robots=ROBOTS, robot_of=robot_of
    )
    try:
        outcome = _scenario(args, folder, timeline)
    finally:
        timeline.close()
    ok = bool(outcome.goals) and all(g.state is GoalState.ACHIEVED for g in outcome.goals)
    elapsed = time.time() - timeline.start
    if args.json:
        print_json(report(outcome, timeline, ok, elapsed))
    else:
        summary(outcome, timeline, elapsed)
    return 0 if ok else 1


def _scenario(args: argparse.Namespace, folder: Path, timeline: Timeline) -> Outcome:
    """Run the deliveries on the example fleet in ``folder``, killing one robot."""
    timeline.say(
        "DEMO",
        f"starting the executives of {listed(ROBOTS)} and the fleet in {folder} "
        f"(robot time runs {SCALE:g} times as fast as the clock)",
    )
    robots = {
        name: RobotProcess(EXAMPLE / f"{name}.yaml", folder / name, time_scale=SCALE)
        for name in ROBOTS
    }
    with contextlib.ExitStack() as stack:
        start_robots(robots.values(), stack)
        path = fleet_variant(EXAMPLE / "fleet.yaml", list(robots.values()), folder)
        timeline.doing("starting the fleet's high level")
        fleet = stack.enter_context(FleetProcess(path, folder / "fleet", time_scale=SCALE))
        timeline.use(fleet.kb_path)
        if args.dashboard is not None:
            _serve(args, stack, path, fleet)
        fleet.bus.subscribe(EVENTS, timeline.on_event)
        joined = [e.subject for e in fleet.events("ROBOT_JOINED")]
        timeline.say(
            "DEMO",
            f"the fleet answers ({listed(joined) or 'no robot'} joined); asking for "
            f"{plural(len(DELIVERIES), 'delivery', 'deliveries')}",
        )
        timeline.doing("planning")
        for parcel, place in DELIVERIES:
            fleet.submit_goal(f"(crate_at {parcel} {place})")
        picking = timeline.wait("START", "pick", timeout=120)
        killed = timeline.robot(picking)
        if killed is None:
            raise DuraError(f"demo: step {picking.subject} names no robot of the fleet")
        timeline.say("KILL", f"SIGKILL of {killed}'s executive while it picks up a parcel")
        robots[killed].kill()
        timeline.wait("ROBOT_LOST", killed)
        deadline = time.monotonic() + TIMEOUT
        while time.monotonic() < deadline and any(g.state.is_open for g in fleet.goals()):
            time.sleep(0.2)
        goals = fleet.goals()
        timeline.doing("stopping the fleet and the executives")
    from knowledge.knowledge_base import KnowledgeBase  # the fleet's log, whole, once it stopped

    with KnowledgeBase(fleet.kb_path, readonly=True) as kb:
        events = kb.events()
    return Outcome(goals, events, killed)


def _serve(
    args: argparse.Namespace, stack: contextlib.ExitStack, path: Path, fleet: FleetProcess
) -> None:
    """Serve the fleet's dashboard while the demo runs (its plan by robot)."""
    from executive.dashboard.server import Dashboard  # the web stack only when asked
    from executive.fleet.description import load_fleet

    dashboard = stack.enter_context(
        Dashboard.connect(load_fleet(path).as_robot(), fleet.endpoint, port=args.dashboard,
                          folders=[fleet.folder], fleet=True)
    )  # fmt: skip
    print(f"dura demo: the fleet's dashboard on {dashboard.url}", flush=True,
          file=sys.stderr if args.json else sys.stdout)  # fmt: skip


def start_robots(robots: Iterable[RobotProcess], stack: contextlib.ExitStack) -> None:
    """Start the robots' executives side by side; each is stopped when ``stack`` closes
    (those that started, if one did not)."""
    robots = list(robots)
    for robot in robots:
        stack.callback(robot.stop)
    with ThreadPoolExecutor(len(robots)) as pool:
        for started in [pool.submit(robot.start) for robot in robots]:
            started.result()


def robot_finder(path: Path) -> RobotOf:
    """The robot of the fleet ``path`` that carries out an action with these arguments."""
    from executive.fleet.validation import check_fleet  # reads the domain: PDDL

    check = check_fleet(path)
    fleet, domain = check.fleet, check.domain
    if not check.ok or fleet is None or domain is None:
        raise DuraError(f"the example fleet is not valid: {check.findings[0]}")

    def robot_of(action: str, args: Sequence[str]) -> str | None:
        parameter = check.actors.get(action)
        if parameter is None:
            return None
        index = domain.actions[action].parameter_names.index(parameter)
        robot = fleet.robot_of_object(args[index]) if index < len(args) else None
        return robot.name if robot is not None else None

    return robot_of


# --- what it says at the end ----------------------------------------------------------


def delivered_by(events: Sequence[Event], timeline: Timeline) -> dict[str, str]:
    """The robot that delivered each parcel: the robot of its last drop that ended."""
    robots: dict[str, str] = {}
    for e in events:
        if e.kind == "END" and e.data.get("action") == "drop":
            robot = timeline.robot(e)
            robots[str(e.data["args"][1])] = robot or "-"
    return robots


def robot_steps(events: Sequence[Event], timeline: Timeline) -> dict[str, list[Event]]:
    """Each robot's step events (START, END, FAIL, CANCEL) in the log's order."""
    steps: dict[str, list[Event]] = {name: [] for name in ROBOTS}
    for e in events:
        robot = timeline.robot(e) if e.kind in ("START", *STEP_ENDS) else None
        if robot is not None:
            steps[robot].append(e)
    return steps


def lost_robots(events: Sequence[Event]) -> dict[str, str]:
    """The robots the fleet lost and had not back at the end, with why."""
    lost: dict[str, str] = {}
    for e in events:
        if e.kind == "ROBOT_LOST":
            lost[e.subject] = str(e.data.get("reason", ""))
        elif e.kind == "ROBOT_JOINED":
            lost.pop(e.subject, None)
    return lost


def busy(steps: Sequence[Event], start: float, span: float) -> str:
    """A robot's timeline: ``█`` while one of its steps ran (from its start to its end),
    on a time axis of ``span`` seconds from ``start``."""
    cells = [" "] * BAR
    began: dict[str, float] = {}
    for e in steps:
        if e.kind == "START":
            began[e.subject] = e.stamp
        elif e.subject in began:
            first = int((began.pop(e.subject) - start) / span * BAR)
            last = max(first + 1, round((e.stamp - start) / span * BAR))
            for i in range(max(0, first), min(BAR, last)):
                cells[i] = "█"
    return "|" + "".join(cells) + "|"


def summary(outcome: Outcome, timeline: Timeline, elapsed: float) -> None:
    """The goals and who delivered each, each robot's work on one time axis, the counts."""
    events, goals = outcome.events, outcome.goals
    by = delivered_by(events, timeline)
    section("goals")
    table(
        ["id", "goal", "state", "took", "delivered by"],
        [
            [g.id, g.expression, g.state.value, seconds(round(g.updated - g.created, 1)),
             _delivered(g, by)]
            for g in goals
        ],
    )  # fmt: skip
    steps = robot_steps(events, timeline)
    stamps = [e.stamp for robot in steps.values() for e in robot]
    start = min(stamps, default=0.0)
    span = (max(stamps, default=0.0) - start) or 1.0
    lost = lost_robots(events)
    ever = {e.subject for e in events if e.kind == "ROBOT_LOST"}
    section(f"robots (their steps over {seconds(round(span, 1))})")
    table(
        ["robot", "state", "ended", "failed", "timeline"],
        [
            [name, f"lost: {lost[name]}" if name in lost else "available",
             sum(e.kind == "END" for e in done), sum(e.kind == "FAIL" for e in done),
             busy(done, start, span)]
            for name, done in steps.items()
        ],
    )  # fmt: skip
    kinds = [e.kind for e in events]
    replanned = replans(events)
    which = f" (plan {', '.join(map(str, replanned))})" if replanned else ""
    section(
        f"{plural(len(events), 'event')}, {plural(kinds.count('PLAN_START'), 'plan')} started, "
        f"{plural(len(replanned), 'replan')}{which}, "
        f"{plural(kinds.count('DISPATCH'), 'step')} dispatched, "
        f"{plural(len(ever), 'robot')} lost ({listed(sorted(ever)) or 'none'}), "
        f"in {elapsed:.1f} s"
    )
    achieved = sum(g.state is GoalState.ACHIEVED for g in goals)
    print(f"{achieved} of {plural(len(goals), 'goal')} achieved", flush=True)


def report(outcome: Outcome, timeline: Timeline, ok: bool, elapsed: float) -> dict[str, Any]:
    """``--json``: the outcome, each goal with its state and the robot that delivered it,
    each robot, the replans, the robots lost, and every event (with its robot)."""
    events = outcome.events
    by = delivered_by(events, timeline)
    lost = lost_robots(events)
    robots = [
        {"robot": name, "available": name not in lost, "reason": lost.get(name),
         "ended": sum(e.kind == "END" for e in done),
         "failed": sum(e.kind == "FAIL" for e in done)}
        for name, done in robot_steps(events, timeline).items()
    ]  # fmt: skip
    return {
        "ok": ok,
        "elapsed": round(elapsed, 2),
        "killed": outcome.killed,
        "robots": robots,
        "goals": [{**plain(g), "robot": _delivered(g, by)} for g in outcome.goals],
        "plans": timeline.plans,
        "replans": len(replans(events)),
        "lost": sorted({e.subject for e in events if e.kind == "ROBOT_LOST"}),
        "events": [_with_robot(plain(e), timeline.robot(e)) for e in events],
    }


def _delivered(goal: Goal, by: Mapping[str, str]) -> str | None:
    """The robot that delivered the parcel of an achieved goal ``(crate_at PARCEL PLACE)``."""
    return by.get(goal.expression.split()[1]) if goal.state is GoalState.ACHIEVED else None


def _with_robot(event: Mapping[str, Any], robot: str | None) -> dict[str, Any]:
    return {**event, "robot": robot} if robot is not None else dict(event)
