"""``dura task start|list|stop|pause|resume``: the task executor of a running robot, by
hand (the thesis' text interface)."""

from __future__ import annotations

import argparse
from typing import Any

from executive.bus.api import tasks as api
from executive.bus.reports import ExecutorTask
from executive.bus.schema import plain
from executive.cli.arguments import seconds
from executive.cli.client import add_client_options, ask
from executive.cli.output import add_json_flag, print_json, table
from knowledge.errors import DuraError


def register(sub: Any) -> None:
    p = sub.add_parser("task", help="start, list, stop, pause and resume tasks by hand")
    tsub = p.add_subparsers(dest="task_command", metavar="TASK_COMMAND")
    tsub.required = True
    start = tsub.add_parser(
        "start",
        help="start a task: a task (or behavior) of the robot with its goal fields",
        description="Ask the task executor for a task: TASK is a task of the robot "
        "description (e.g. move_to) or a behavior; --arg sets a field of the behavior's "
        "goal (e.g. --arg start=dock --arg target=lab). It runs once its configuration "
        "is scheduled and ready.",
    )
    start.add_argument(
        "task", metavar="TASK", help="a task of the robot description, or a behavior"
    )
    start.add_argument(
        "--arg", action="append", default=[], metavar="K=V", help="a goal field (repeatable)"
    )
    start.add_argument("--duration", type=seconds(), metavar="S", help="the expected duration")
    start.add_argument(
        "--earliest",
        type=seconds(zero=True),
        metavar="S",
        help="start no sooner than S seconds from now",
    )
    start.add_argument(
        "--deadline",
        type=seconds(),
        metavar="S",
        help="end within S seconds from now, or never start",
    )
    start.add_argument(
        "--with", dest="together", action="append", default=[], metavar="ID",
        help="start together with this waiting task (repeatable)",
    )  # fmt: skip
    start.set_defaults(run=run_start)
    listing = tsub.add_parser("list", help="every task with its state and configuration")
    listing.set_defaults(run=run_list)
    commands = [start, listing]
    for verb, text in (
        ("stop", "stop a task (cancelled)"),
        ("pause", "pause a running task"),
        ("resume", "resume a paused task"),
    ):
        cmd = tsub.add_parser(verb, help=text)
        cmd.add_argument("id", metavar="ID", help="the task's id (dura task list)")
        cmd.set_defaults(run=run_verb, verb=verb)
        commands.append(cmd)
    for cmd in commands:
        add_client_options(cmd)
        add_json_flag(cmd)


def _goal(pairs: list[str]) -> dict[str, Any]:
    goal: dict[str, Any] = {}
    for pair in pairs:
        key, sep, value = pair.partition("=")
        if not sep or not key:
            raise DuraError(f"--arg must be KEY=VALUE, not '{pair}'")
        goal[key] = value
    return goal


def run_start(args: argparse.Namespace) -> int:
    request = api.TaskStart(
        args.task, _goal(args.arg), args.duration, args.earliest, args.deadline, args.together
    )
    reply = ask(args, api.TASK_START, request)
    if args.json:
        print_json(reply.to_payload())
    else:
        print(f"task {reply.id}: {request.label} requested")
    return 0


def _rows(tasks: list[ExecutorTask]) -> list[list[Any]]:
    return [[t.id, t.name, t.state, ", ".join(t.functionalities) or "-", t.reason] for t in tasks]


def run_list(args: argparse.Namespace) -> int:
    tasks = ask(args, api.TASK_LIST).tasks
    if args.json:
        print_json({"tasks": plain(tasks)})
    else:
        table(["id", "task", "state", "uses", "reason"], _rows(tasks))
    return 0


def run_verb(args: argparse.Namespace) -> int:
    verb = {"stop": api.TASK_STOP, "pause": api.TASK_PAUSE, "resume": api.TASK_RESUME}[args.verb]
    task = ask(args, verb, api.TaskId(args.id)).task
    if args.json:
        print_json(plain(task))
    else:
        print(f"task {task.id}: {task.state}")
    return 0
