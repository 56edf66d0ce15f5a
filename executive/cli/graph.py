"""``dura graph ROBOT.yaml``: the robot's component graph, as a table or an SVG picture."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Any

from executive.bus.api import planning, tasks
from executive.cli.client import ask
from executive.cli.output import shown, table
from executive.dashboard import graph
from executive.dashboard.live import LiveState
from knowledge.robot import load_robot


def register(sub: Any) -> None:
    p = sub.add_parser(
        "graph",
        help="the component graph of a robot (functionalities, behaviors, capabilities, topics)",
        description="Print the component graph of a robot description: each component with "
        "what it provides, requires, publishes and subscribes. --svg FILE draws it instead "
        "(components, capabilities and topics, left to right along the capabilities). "
        "--diagnoses asks the robot's running executive for its state and draws it over the "
        "graph: components coloured by state, the current diagnoses highlighted, fault "
        "counters and the active configurations.",
    )
    p.add_argument("robot", metavar="ROBOT.yaml", type=Path, help="the robot description")
    p.add_argument("--svg", metavar="FILE", help="write the graph as an SVG picture ('-': stdout)")
    p.add_argument(
        "--diagnoses",
        action="store_true",
        help="draw the running executive's state: component states, diagnoses, faults",
    )
    p.add_argument(
        "--endpoint",
        help="where the executive listens (default: where the one that runs in this folder "
        "does, if it is this robot's; else where the description says)",
    )
    p.set_defaults(run=run)


def live_state(args: argparse.Namespace) -> LiveState:
    """The robot's state as its running executive reports it."""
    robot = load_robot(args.robot)
    state = LiveState(robot)
    status = ask(args, planning.STATUS)
    state.set_diagnosis(status.diagnosis)
    if isinstance(status.components, list):
        state.set_components(status.components)
    if isinstance(status.tasks, list):
        state.set_tasks(status.tasks)
    state.set_faults(status.faults, ask(args, tasks.SCHEDULE_SHOW).faulty)
    return state


def run(args: argparse.Namespace) -> int:
    robot = load_robot(args.robot)
    layout = graph.layout(robot)
    state = live_state(args).graph_state() if args.diagnoses else None
    if args.svg is not None:
        picture = graph.render(layout, state)
        if args.svg == "-":
            sys.stdout.write(picture)
        else:
            Path(args.svg).write_text(picture, encoding="utf-8")
            print(f"{shown(args.svg)}: the graph of robot '{robot.name}'")
        return 0
    rows = []
    for name, spec in robot.components.items():
        row = [name, spec.kind.value]
        if state is not None:
            row.append(
                state.states.get(name, "stopped")
                + (" (diagnosed)" if name in state.diagnosed else "")
            )
        provides = getattr(spec, "provides", ())
        rows.append([*row, list(provides), list(spec.requires), list(spec.publishes),
                     list(spec.subscribes)])  # fmt: skip
    headers = ["component", "kind", *(["state"] if state is not None else []), "provides",
               "requires", "publishes", "subscribes"]  # fmt: skip
    table(headers, rows)
    return 0
