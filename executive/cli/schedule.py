"""``dura schedule show``: the task executor's schedule, tasks in time and the
functionalities they use."""

from __future__ import annotations

import argparse
from typing import Any

from executive.bus.api import tasks as api
from executive.cli.client import add_client_options, ask
from executive.cli.output import add_json_flag, bar, print_json, section, table


def register(sub: Any) -> None:
    s = sub.add_parser("schedule", help="the schedule: tasks in time and what they use")
    ssub = s.add_subparsers(dest="schedule_command", metavar="SCHEDULE_COMMAND")
    ssub.required = True
    show = ssub.add_parser("show", help="a timeline of the tasks and their functionalities")
    show.set_defaults(run=run_schedule)
    add_client_options(show)
    add_json_flag(show)


def run_schedule(args: argparse.Namespace) -> int:
    schedule = ask(args, api.SCHEDULE_SHOW)
    if args.json:
        print_json(schedule.to_payload())
        return 0
    tasks = schedule.tasks
    span = max((t.end for t in tasks), default=0.0)
    first = min((t.start for t in tasks), default=0.0)
    table(
        ["id", "task", "state", "start", "end", "uses", "timeline"],
        [
            [t.id, t.name, t.state, f"{t.start:+.1f}", f"{t.end:+.1f}",
             ", ".join(t.functionalities) or "-", bar(t.start - first, t.end - t.start, span - first)]
            for t in tasks
        ],
    )  # fmt: skip
    section(
        f"running: {', '.join(schedule.running) or 'nothing'}; "
        f"permanently faulty: {', '.join(schedule.faulty) or 'none'}"
    )
    return 0
