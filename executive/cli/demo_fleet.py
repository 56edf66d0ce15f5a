"""``dura demo --fleet``: three transport robots share the depot's deliveries
(``examples/fleet``), and one of them is lost mid-plan.

It starts the executive of each robot (each its own process and bus login) and the
fleet's high level in a temporary folder, submits three deliveries, kills (SIGKILL) the
executive of the first robot that starts a step, and ends when the others have finished
its deliveries too: exit 0 if every goal is achieved, 1 with the reason if not.
"""

from __future__ import annotations

import argparse
import contextlib
import tempfile
import time
from pathlib import Path
from typing import Any

from executive.bus.keys import EVENTS
from executive.bus.schema import plain
from executive.bus.wording import plural
from executive.cli.demo_timeline import Timeline, replans
from executive.cli.output import print_json, section, table
from executive.testing.fleet import FleetProcess, fleet_variant
from executive.testing.harness import RobotProcess
from knowledge.errors import DuraError
from knowledge.records import Event, Goal, GoalState

EXAMPLE = Path(__file__).resolve().parents[2] / "examples" / "fleet"
ROBOTS = ("r1", "r2", "r3")
GOALS = ("(crate_at parcel1 lab)", "(crate_at parcel2 office)", "(crate_at parcel3 lab)")
SCALE = 2.0  # robot time twice as fast as the wall clock
TIMEOUT = 120.0  # seconds for the deliveries once the robot is lost


def run(args: argparse.Namespace) -> int:
    if not (EXAMPLE / "fleet.yaml").is_file():
        raise DuraError(f"the example fleet is missing: {EXAMPLE} (run from a dura checkout)")
    if args.keep is not None:
        args.keep.mkdir(parents=True, exist_ok=True)
        return _demo(args, args.keep.resolve())
    with tempfile.TemporaryDirectory(prefix="dura-demo-fleet-") as folder:
        return _demo(args, Path(folder))


def _demo(args: argparse.Namespace, folder: Path) -> int:
    timeline = Timeline(quiet=args.json, everything=args.all_events)
    try:
        goals, robots, lost = _scenario(folder, timeline)
    finally:
        timeline.close()
    return _outcome(args, goals, robots, lost, timeline)


def _scenario(folder: Path, timeline: Timeline) -> tuple[list[Goal], list[Any], list[str]]:
    """Run the deliveries in ``folder``: the goals, the robots and those lost at the end."""
    timeline.say("DEMO", f"starting the executives of {', '.join(ROBOTS)} in {folder}")
    with contextlib.ExitStack() as stack:
        robots = {
            name: stack.enter_context(
                RobotProcess(EXAMPLE / f"{name}.yaml", folder / name, time_scale=SCALE)
            )
            for name in ROBOTS
        }
        timeline.doing("starting the fleet")
        description = fleet_variant(EXAMPLE / "fleet.yaml", list(robots.values()), folder)
        fleet = stack.enter_context(FleetProcess(description, folder / "fleet", time_scale=SCALE))
        timeline.use(fleet.kb_path)
        fleet.bus.subscribe(EVENTS, timeline.on_event)
        timeline.say("DEMO", f"the fleet plans for {len(ROBOTS)} robots; {len(GOALS)} deliveries")
        for expression in GOALS:
            fleet.submit_goal(expression)
        started = timeline.wait("START")
        victim = _robot_of(started)
        lost: list[str] = []
        if victim in robots:
            timeline.say("KILL", f"the executive of {victim} is killed (SIGKILL) mid-step")
            robots[victim].kill()
            lost.append(victim)
        deadline = time.monotonic() + TIMEOUT
        while time.monotonic() < deadline:
            if not any(g.state.is_open for g in fleet.goals()):
                break
            time.sleep(0.2)
        timeline.doing("stopping the fleet and the robots")
        status = fleet.status()
        return fleet.goals(), plain(status.robots or []), lost


def _robot_of(event: Event) -> str:
    return str(event.data.get("robot", ""))


def _event(event: Event) -> dict[str, Any]:
    """An event for ``--json``: a plan step's names its robot."""
    shown: dict[str, Any] = plain(event)
    if event.data.get("robot"):
        shown["robot"] = event.data["robot"]
    return shown


def _outcome(
    args: argparse.Namespace,
    goals: list[Goal],
    robots: list[Any],
    lost: list[str],
    timeline: Timeline,
) -> int:
    ok = bool(goals) and all(g.state is GoalState.ACHIEVED for g in goals)
    elapsed = time.time() - timeline.start
    if args.json:
        print_json(
            {"ok": ok, "elapsed": round(elapsed, 2), "robots": robots, "goals": plain(goals),
             "replans": len(replans(timeline.events)), "lost": lost,
             "events": [_event(e) for e in timeline.events]}
        )  # fmt: skip
        return 0 if ok else 1
    section("deliveries")
    table(
        ["id", "goal", "state", "robot", "reason"],
        [[g.id, g.expression, g.state.value, _deliverer(g, timeline.events), g.reason]
         for g in goals],
    )  # fmt: skip
    section(
        f"{plural(len(lost), 'robot')} lost ({', '.join(lost) or 'none'}), "
        f"{plural(len(replans(timeline.events)), 'replan')}, in {elapsed:.1f} s"
    )
    achieved = sum(g.state is GoalState.ACHIEVED for g in goals)
    print(f"{achieved} of {plural(len(goals), 'delivery', 'deliveries')} achieved", flush=True)
    return 0 if ok else 1


def _deliverer(goal: Goal, events: list[Event]) -> str:
    """The robot whose drop ended with the goal's crate where it wanted it."""
    crate_place = goal.expression.strip("()").split()[1:]
    for event in events:
        if event.kind == "END" and event.data.get("action") == "drop":
            args = event.data.get("args", [])
            if args[1:] == crate_place:
                return _robot_of(event)
    return "-"
