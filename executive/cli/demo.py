"""``dura demo``: the thesis use case end to end, on the embedded example robot.

It starts the executive of ``examples/usecase/robot.yaml`` in a temporary folder,
submits goals (pictures of the lab and the office, then back to the dock), shows the
plan, makes lidar stop publishing while the robot drives — the observers see it, the
diagnosis names lidar, a repair rule restarts it — until lidar is permanently faulty,
and shows the switch to cam + cam_to_lidar, and ends with a summary when every goal
is achieved: exit 0, or 1 with the reason if the robot did not get there.
"""

from __future__ import annotations

import argparse
import contextlib
import queue
import sys
import tempfile
import threading
import time
from pathlib import Path
from typing import Any

from executive.bus.api.planning import PLAN_SHOW
from executive.bus.api.tasks import TASK_LIST
from executive.bus.keys import DIAGNOSES, EVENTS
from executive.bus.session import Message
from executive.cli.dashboard import port
from executive.cli.goal import details
from executive.cli.output import add_json_flag, print_json, section, table
from executive.cli.plan import bar
from executive.dashboard.access import DEFAULT_PORT
from executive.testing.harness import RobotProcess
from knowledge.errors import DuraError

EXAMPLE = Path(__file__).resolve().parents[2] / "examples" / "usecase" / "robot.yaml"
GOALS = (
    ("(picture_taken lab)", 1),
    ("(picture_taken office)", 1),
    ("(and (robot_at dock) (picture_taken lab) (picture_taken office))", 0),
)
FAULTS = 3  # lidar's max_faults in the example
TIMEOUT = 120.0  # seconds for the whole run

# What a person wants to see of the event log; the rest is there with --verbose.
SHOWN = {
    "GOAL_ADDED", "GOAL_PLANNED", "GOAL_ACHIEVED", "GOAL_FAILED", "GOAL_UNREACHABLE",
    "PLAN_START", "DISPATCH", "START", "END", "FAIL", "REPLAN", "CANCEL",
    "COMPONENT_READY", "COMPONENT_EXITED", "COMPONENT_FAILED", "FAULT", "PERMANENT_FAULT",
    "INTEGRITY_GOAL", "CONFIGURATION", "TASK_FAILED", "TASK_PAUSED", "TASK_RESUMED",
    "REPAIR", "TASK_RESTARTED", "RULE_FIRED", "RULE_FAILED",
}  # fmt: skip


def register(sub: Any) -> None:
    p = sub.add_parser(
        "demo",
        help="run the thesis use case end to end (about a minute)",
        description="Start the example robot, submit goals, stop lidar's scan until it is "
        "permanently faulty, watch the diagnosis and the switch to the camera, and print a "
        "summary once every goal is achieved. Exit 0 if they all are.",
    )
    p.add_argument("--keep", type=Path, metavar="DIR", help="run in DIR and keep its files")
    p.add_argument(
        "--ros2",
        action="store_true",
        help="run the ROS 2 patrol robot (examples/ros2) instead: ROS 2 nodes, a managed "
        "node, an action and a service as tasks, a goal from ROS 2, on loopback DDS",
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


class Timeline:
    """Prints events and diagnoses as they come, relative to the demo's start."""

    def __init__(self, quiet: bool, everything: bool) -> None:
        self.start = time.time()
        self.quiet = quiet
        self.everything = everything
        self.events: list[dict[str, Any]] = []
        self.diagnoses: list[dict[str, Any]] = []
        self.arrived: queue.Queue[dict[str, Any]] = queue.Queue()
        self._lock = threading.Lock()
        self._last_diagnosis = ""

    def say(self, text: str) -> None:
        if not self.quiet:
            print(f"{time.time() - self.start:6.1f}s  {text}", flush=True)

    def on_event(self, message: Message) -> None:
        event = message.payload
        with self._lock:
            self.events.append(event)
        self.arrived.put(event)
        if self.everything or event.get("kind") in SHOWN:
            more = details(event.get("data") or {})
            self.say(f"{event.get('kind', '?'):<17} {event.get('subject', '')}  {more}".rstrip())

    def on_diagnoses(self, message: Message) -> None:
        payload = message.payload
        found = " or ".join("{" + ", ".join(d) + "}" for d in payload.get("diagnoses", []))
        shown = f"{payload.get('status')} {found}".strip()
        with self._lock:
            self.diagnoses.append(payload)
            if shown == self._last_diagnosis:
                return
            self._last_diagnosis = shown
        self.say(f"{'DIAGNOSIS':<17} {shown}")

    def wait(self, kind: str, subject: str = "", timeout: float = 60.0) -> dict[str, Any]:
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
            about = str(event.get("subject", ""))
            if event.get("kind") == kind and (
                not subject or about == subject or about.startswith(subject + "(")
            ):
                return event


def run(args: argparse.Namespace) -> int:
    if args.ros2:  # Cyclone DDS loads only for this one
        from executive.cli import demo_ros2

        return demo_ros2.run(args)
    if not EXAMPLE.is_file():
        raise DuraError(f"the example robot is missing: {EXAMPLE} (run from a dura checkout)")
    if args.keep is not None:
        args.keep.mkdir(parents=True, exist_ok=True)
        return _demo(args, args.keep)
    with tempfile.TemporaryDirectory(prefix="dura-demo-") as folder:
        return _demo(args, Path(folder))


def _demo(args: argparse.Namespace, folder: Path) -> int:
    timeline = Timeline(quiet=args.json, everything=args.all_events)
    say = timeline.say
    say(f"starting the executive of the thesis use case in {folder}")
    with RobotProcess(EXAMPLE, folder) as robot, contextlib.ExitStack() as page:
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
        ids = []
        for expression, priority in GOALS:
            ids.append(robot.submit_goal(expression, priority=priority))
            say(f"{'SUBMIT':<17} goal {ids[-1]}: {expression}")
        timeline.wait("PLAN_START")
        _show_plan(robot, args.json)
        for fault in range(1, FAULTS + 1):
            # one fault a drive, while move_to runs on lidar: the diagnosis names lidar,
            # and the repair rule (which waits its recall_duration before it acts again)
            # restarts it; after the last one the robot drives on the camera
            while True:
                timeline.wait("START", "move_to")
                time.sleep(1.0)  # let it drive a little
                if _driving_on_lidar(robot):
                    break
            say(f"{'INJECT':<17} lidar stops publishing its scan ({fault} of {FAULTS})")
            robot.inject_fault("lidar", "stop_publishing")
            timeline.wait("FAULT", "lidar")
        deadline = time.monotonic() + TIMEOUT
        while time.monotonic() < deadline:
            goals = robot.goals()
            if all(g["state"] not in ("pending", "planned", "executing") for g in goals):
                break
            time.sleep(0.2)
        goals = robot.goals()
        status = robot.status()
    ok = all(g["state"] == "achieved" for g in goals)
    elapsed = time.time() - timeline.start
    if args.json:
        print_json(
            {"ok": ok, "elapsed": round(elapsed, 2), "goals": goals, "faults": status["faults"],
             "events": timeline.events, "diagnoses": timeline.diagnoses}
        )  # fmt: skip
        return 0 if ok else 1
    _summary(goals, status, timeline, elapsed)
    return 0 if ok else 1


def _driving_on_lidar(robot: RobotProcess) -> bool:
    tasks = TASK_LIST.call(robot.bus).tasks
    return any(
        t["behavior"] == "move_to" and t["state"] == "running" and "lidar" in t["functionalities"]
        for t in tasks
    )


def _show_plan(robot: RobotProcess, quiet: bool) -> None:
    if quiet:
        return
    plan = PLAN_SHOW.call(robot.bus).plan
    if plan is None:
        return
    span = max((s["start"] + (s["duration"] or 0.0) for s in plan["steps"]), default=0.0)
    section(f"plan {plan['id']} by {plan['engine']}: {len(plan['steps'])} steps, {span:g} s")
    table(
        ["#", "start", "step", "timeline"],
        [
            [s["index"], f"{s['start']:.1f}", f"{s['action']}({', '.join(s['args'])})",
             bar(s["start"], s["duration"], span)]
            for s in plan["steps"]
        ],
    )  # fmt: skip
    print(flush=True)


def _summary(
    goals: list[dict[str, Any]], status: dict[str, Any], timeline: Timeline, elapsed: float
) -> None:
    section("goals")
    table(
        ["id", "goal", "state", "took", "reason"],
        [
            [g["id"], g["expression"], g["state"], f"{g['updated'] - g['created']:.1f} s",
             g["reason"]]
            for g in goals
        ],
    )  # fmt: skip
    faults = status.get("faults") or []
    if faults:
        section("component faults")
        table(
            ["component", "faults", "permanently faulty", "reason"],
            [[f["name"], f["fault_count"], f["permanent_fault"], f["reason"]] for f in faults],
        )
    switches: list[str] = []
    for e in timeline.events:
        if e.get("kind") == "TASK_STARTED" and e.get("data", {}).get("behavior") == "move_to":
            uses = " + ".join(sorted(set(e["data"].get("providers", {}).values())))
            if not switches or switches[-1] != uses:
                switches.append(uses)
    if switches:
        section("move_to drove on: " + "  ->  ".join(switches))
    kinds = [e.get("kind") for e in timeline.events]
    section(
        f"{len(timeline.events)} events, {kinds.count('PLAN_START')} plans, "
        f"{kinds.count('DISPATCH')} tasks dispatched, {kinds.count('REPLAN')} replans, "
        f"{len(timeline.diagnoses)} diagnosis results, in {elapsed:.1f} s"
    )
    achieved = sum(g["state"] == "achieved" for g in goals)
    print(f"{achieved} of {len(goals)} goals achieved", flush=True)
