"""``dura demo``: the thesis use case end to end, on the embedded example robot.

It starts the executive of ``examples/usecase/robot.yaml`` in a temporary folder,
submits goals (pictures of the lab and the office, then back to the dock), shows each
plan as it starts (:mod:`executive.cli.demo_timeline` prints what happens), makes lidar stop publishing while the robot drives — the observers see it, the
diagnosis names lidar, a repair rule restarts it — until lidar is permanently faulty,
and shows the switch to cam + cam_to_lidar, and ends with a summary when every goal
is achieved: exit 0, or 1 with the reason if the robot did not get there.
"""

from __future__ import annotations

import argparse
import contextlib
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

from executive.bus.api.planning import StatusReply
from executive.bus.api.tasks import TASK_LIST
from executive.bus.keys import DIAGNOSES, EVENTS
from executive.bus.schema import plain
from executive.bus.wording import plural, seconds
from executive.cli.dashboard import port
from executive.cli.demo_timeline import Timeline, replans
from executive.cli.output import add_json_flag, print_json, section, table
from executive.dashboard.access import DEFAULT_PORT
from executive.testing.harness import RobotProcess
from knowledge.errors import DuraError
from knowledge.records import Goal, GoalState

EXAMPLE = Path(__file__).resolve().parents[2] / "examples" / "usecase" / "robot.yaml"
GOALS = (
    ("(picture_taken lab)", 1),
    ("(picture_taken office)", 1),
    ("(and (robot_at dock) (picture_taken lab) (picture_taken office))", 0),
)
FAULTS = 3  # lidar's max_faults in the example
TIMEOUT = 120.0  # seconds for the whole run


def register(sub: Any) -> None:
    p = sub.add_parser(
        "demo",
        help="run the thesis use case end to end (about 30 s; 45 s or more on a busy machine)",
        description="Start the example robot, submit goals, stop lidar's scan until it is "
        "permanently faulty, watch the diagnosis and the switch to the camera, and print a "
        "summary once every goal is achieved. Exit 0 if they all are. Each plan the robot "
        "executes is shown as it starts, with the plan it replaces and why. It takes about "
        "30 s on a quiet machine (most of it the robot driving) and 45 s or more on a busy "
        "one; on a terminal, the last line says what the robot does now.",
    )
    p.add_argument("--keep", type=Path, metavar="DIR", help="run in DIR and keep its files")
    which = p.add_mutually_exclusive_group()
    which.add_argument(
        "--ros2",
        action="store_true",
        help="run the ROS 2 patrol robot (examples/ros2) instead: ROS 2 nodes, a managed "
        "node, an action and a service as tasks, a goal from ROS 2, on loopback DDS",
    )
    which.add_argument(
        "--fleet",
        action="store_true",
        help="run the depot fleet (examples/fleet) instead: three transport robots deliver "
        "parcels in parallel, one robot's executive is killed mid-plan, the others finish "
        "its deliveries",
    )
    p.add_argument("--all-events", action="store_true", help="show every event")
    p.add_argument(
        "--dashboard",
        nargs="?",
        type=port,
        const=DEFAULT_PORT,
        metavar="PORT",
        help=f"serve the live dashboard while the demo runs (default port {DEFAULT_PORT}) and "
        "print its address",
    )
    add_json_flag(p)
    p.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    if args.ros2:  # Cyclone DDS loads only for this one
        from executive.cli import demo_ros2  # Cyclone DDS

        return demo_ros2.run(args)
    if args.fleet:  # the fleet's example and harness
        from executive.cli import demo_fleet

        return demo_fleet.run(args)
    if not EXAMPLE.is_file():
        raise DuraError(f"the example robot is missing: {EXAMPLE} (run from a dura checkout)")
    if args.keep is not None:
        args.keep.mkdir(parents=True, exist_ok=True)
        return _demo(args, args.keep)
    with tempfile.TemporaryDirectory(prefix="dura-demo-") as folder:
        return _demo(args, Path(folder))


def _demo(args: argparse.Namespace, folder: Path) -> int:
    timeline = Timeline(quiet=args.json, everything=args.all_events)
    try:
        goals, status = _scenario(args, folder, timeline)
    finally:
        timeline.close()
    return _outcome(args, goals, status, timeline)


def _scenario(
    args: argparse.Namespace, folder: Path, timeline: Timeline
) -> tuple[list[Goal], StatusReply]:
    """Run the use case on a robot in ``folder``; the goals and the status at the end."""
    timeline.say("DEMO", f"starting the executive of the thesis use case in {folder}")
    with RobotProcess(EXAMPLE, folder) as robot, contextlib.ExitStack() as page:
        timeline.use(robot.kb_path)
        timeline.doing("submitting goals")
        if args.dashboard is not None:
            from executive.dashboard.server import Dashboard  # the web stack only when asked

            dashboard = page.enter_context(
                Dashboard.connect(robot.robot, robot.endpoint, port=args.dashboard,
                                  folders=[folder])
            )  # fmt: skip
            print(f"dura demo: dashboard on {dashboard.url}", flush=True,
                  file=sys.stderr if args.json else sys.stdout)  # fmt: skip
        robot.bus.subscribe(EVENTS, timeline.on_event)
        robot.bus.subscribe(DIAGNOSES, timeline.on_diagnoses)
        timeline.say("DEMO", f"the executive answers; submitting {len(GOALS)} goals")
        for expression, priority in GOALS:
            robot.submit_goal(expression, priority=priority)
        timeline.wait("PLAN_START")
        for fault in range(1, FAULTS + 1):
            # one fault a drive, while move_to runs on lidar: the diagnosis names lidar,
            # and the repair rule (which waits its recall_duration before it acts again)
            # restarts it; after the last one the robot drives on the camera
            while True:
                timeline.wait("START", "move_to")
                time.sleep(1.0)  # let it drive a little
                if _driving_on_lidar(robot):
                    break
            timeline.say("INJECT", f"lidar stops publishing its scan ({fault} of {FAULTS})")
            robot.inject_fault("lidar", "stop_publishing")
            timeline.wait("FAULT", "lidar")
        deadline = time.monotonic() + TIMEOUT
        while time.monotonic() < deadline:
            if not any(g.state.is_open for g in robot.goals()):
                break
            time.sleep(0.2)
        timeline.doing("stopping the executive")
        return robot.goals(), robot.status()


def _outcome(
    args: argparse.Namespace, goals: list[Goal], status: StatusReply, timeline: Timeline
) -> int:
    ok = all(g.state is GoalState.ACHIEVED for g in goals)
    elapsed = time.time() - timeline.start
    if args.json:
        print_json(
            {"ok": ok, "elapsed": round(elapsed, 2), "goals": plain(goals),
             "faults": plain(status.faults), "plans": timeline.plans,
             "replans": len(replans(timeline.events)), "events": plain(timeline.events),
             "diagnoses": timeline.diagnoses}
        )  # fmt: skip
        return 0 if ok else 1
    summary(goals, status, timeline, elapsed)
    return 0 if ok else 1


def _driving_on_lidar(robot: RobotProcess) -> bool:
    tasks = TASK_LIST.call(robot.bus).tasks
    return any(
        t.behavior == "move_to" and t.state == "running" and "lidar" in t.functionalities
        for t in tasks
    )


def summary(goals: list[Goal], status: StatusReply, timeline: Timeline, elapsed: float) -> None:
    """The goals, the faults, what move_to drove on and the counts, after the timeline."""
    section("goals")
    table(
        ["id", "goal", "state", "took", "reason"],
        [
            [g.id, g.expression, g.state.value, seconds(round(g.updated - g.created, 1)),
             g.reason]
            for g in goals
        ],
    )  # fmt: skip
    if status.faults:
        section("component faults")
        table(
            ["component", "faults", "permanently faulty", "reason"],
            [[f.name, f.fault_count, f.permanent_fault, f.reason] for f in status.faults],
        )
    switches: list[str] = []
    for e in timeline.events:
        if e.kind == "TASK_STARTED" and e.data.get("behavior") == "move_to":
            uses = " + ".join(sorted(set(e.data.get("providers", {}).values())))
            if not switches or switches[-1] != uses:
                switches.append(uses)
    if switches:
        section("move_to drove on: " + "  ->  ".join(switches))
    kinds = [e.kind for e in timeline.events]
    replanned = replans(timeline.events)
    which = f" (plan {', '.join(map(str, replanned))})" if replanned else ""
    started = kinds.count("PLAN_START")
    # a plan replaced before its first step started but ran nothing: counted apart
    ran = len({e.data.get("plan") for e in timeline.events if e.kind == "DISPATCH"})
    section(
        f"{plural(len(timeline.events), 'event')}, "
        f"{plural(started, 'plan')} started"
        + (f" ({started - ran} replaced before its first step)" if ran < started else "")
        + ", "
        f"{plural(len(replanned), 'replan')}{which}, "
        f"{plural(kinds.count('DISPATCH'), 'step')} dispatched, "
        f"{plural(len(timeline.diagnoses), 'diagnosis result')}, in {elapsed:.1f} s"
    )
    achieved = sum(g.state is GoalState.ACHIEVED for g in goals)
    print(f"{achieved} of {plural(len(goals), 'goal')} achieved", flush=True)
