"""``dura goal add|list|show|cancel|watch``: the goal submission interface of a running
robot; ``add --wait`` and ``watch`` follow a goal until it ends."""

from __future__ import annotations

import argparse
import sys
import threading
import time
from typing import Any, TextIO

from executive.bus.api import planning as api
from executive.bus.keys import EVENTS
from executive.bus.message import Message
from executive.bus.schema import plain
from executive.bus.session import Bus
from executive.cli import exits_at_once
from executive.cli.arguments import count, identifier, priority, seconds
from executive.cli.client import add_client_options, ask, connect
from executive.cli.output import add_json_flag, print_json, table
from knowledge.errors import DuraError
from knowledge.records import Goal
from knowledge.transitions import GoalState

REFRESH = 0.2  # seconds at least between two looks at the goal while following it
CHECK = 2.0  # seconds at most between two looks (should an event be missed)
ACTIVE_STEPS = ("dispatched", "running", "paused")


def register(sub: Any) -> None:
    p = sub.add_parser("goal", help="submit, list, show, cancel and watch goals")
    exits_at_once(p)
    gsub = p.add_subparsers(dest="goal_command", metavar="GOAL_COMMAND")
    gsub.required = True

    add = gsub.add_parser(
        "add",
        help="submit a goal: a PDDL goal expression",
        description="Submit a PDDL goal expression, e.g. '(picture_taken lab)' or "
        "'(and (robot_at dock) (picture_taken office))'. A goal naming unknown predicates "
        "or objects is refused with the reason.",
    )
    add.add_argument("expression", metavar="EXPR", help="the goal expression")
    add.add_argument(
        "--deadline", type=seconds(), metavar="S", help="seconds from now by which it must hold"
    )
    add.add_argument(
        "--priority", type=priority, default=0, metavar="P", help="higher goals win (default 0)"
    )
    _add_wait_options(add, flag=True)
    add.add_argument(
        "--keep",
        action="store_true",
        help="a maintenance goal: once achieved it is watched, and posted again whenever it "
        "stops holding",
    )
    add.set_defaults(run=run_add)

    listing = gsub.add_parser(
        "list",
        help="every goal with its state",
        description="List the goals of a running robot: state, priority, deadline, where "
        "each came from (user, integrity, rule) and why it is where it is.",
    )
    listing.add_argument(
        "--open", action="store_true", help="only goals not yet achieved, failed or cancelled"
    )
    listing.add_argument(
        "-n", "--lines", type=count, metavar="N", help="only the newest N goals (all without)"
    )
    listing.set_defaults(run=run_list)

    show = gsub.add_parser("show", help="one goal and its history")
    show.add_argument("id", type=identifier, metavar="ID", help="the goal's id")
    show.set_defaults(run=run_show)

    cancel = gsub.add_parser("cancel", help="cancel an open goal (the others are replanned)")
    cancel.add_argument("id", type=identifier, metavar="ID", help="the goal's id")
    cancel.set_defaults(run=run_cancel)

    watch = gsub.add_parser(
        "watch",
        help="follow a goal until it ends: exit 0 if achieved, 1 otherwise",
        description="Follow a goal until it is achieved (exit 0), or fails, is unreachable "
        "or cancelled (exit 1, with the reason). On a terminal a line shows how it stands "
        "(state, time, the plan's progress); elsewhere each change of state is a line; with "
        "--json only the goal as it ended is printed.",
    )
    watch.add_argument("id", type=identifier, metavar="ID", help="the goal's id")
    _add_wait_options(watch, flag=False)
    watch.set_defaults(run=run_watch)

    for cmd in (add, listing, show, cancel, watch):
        add_client_options(cmd)
        add_json_flag(cmd)


def _add_wait_options(parser: Any, *, flag: bool) -> None:
    if flag:
        parser.add_argument(
            "--wait",
            action="store_true",
            help="wait until the goal ends: exit 0 if achieved, 1 with the reason otherwise",
        )
    parser.add_argument(
        "--timeout",
        type=seconds(),
        metavar="S",
        help="give up waiting after S seconds (exit 1; the goal goes on)",
    )


def clock(stamp: float) -> str:
    return time.strftime("%H:%M:%S", time.localtime(stamp)) if stamp else "-"


def state_of(goal: Goal) -> str:
    """A goal's state as shown: a maintenance goal that is achieved is watched."""
    if goal.keep and goal.state is GoalState.ACHIEVED:
        return "achieved, watched"
    return goal.state.value


def goal_rows(goals: list[Goal]) -> list[list[Any]]:
    return [
        [
            g.id,
            state_of(g),
            "keep" if g.keep else "once",
            g.priority,
            "-" if g.deadline is None else f"{g.deadline:g} s",
            g.source,
            g.expression,
            g.reason,
        ]
        for g in goals
    ]


GOAL_HEADERS = ["id", "state", "kind", "priority", "deadline", "source", "goal", "reason"]

MEANING = {
    "achieved": "it held when the executive checked it, at {updated}; it is not watched "
    "since (a goal added with --keep is)",
    "achieved, watched": "a maintenance goal: it held when last checked, at {updated}; it is "
    "watched and posted again whenever it stops holding",
    "unreachable": "no plan reached it; it is looked at again when the world changes (a fact "
    "or object set, a component reset or repaired)",
}


def run_add(args: argparse.Namespace) -> int:
    request = api.GoalAdd(args.expression, args.priority, args.deadline, keep=args.keep)
    if not args.wait:
        goal = ask(args, api.GOAL_ADD, request).goal
        if args.json:
            print_json(plain(goal))
        else:
            kept = ", kept" if goal.keep else ""
            print(f"goal {goal.id}: {goal.expression} ({goal.state.value}{kept})")
        return 0
    with connect(args) as bus:
        follower = GoalFollower(bus)  # before the goal exists: no change is missed
        goal = api.GOAL_ADD.call(bus, request).goal
        if not args.json:
            print(f"goal {goal.id}: {goal.expression} ({goal.state.value})", flush=True)
        return _outcome(follower.follow(goal, _view(args), args.timeout), args)


def run_watch(args: argparse.Namespace) -> int:
    with connect(args) as bus:
        follower = GoalFollower(bus)
        goal = api.GOAL_SHOW.call(bus, api.GoalId(args.id)).goal
        return _outcome(follower.follow(goal, _view(args), args.timeout), args)


def _view(args: argparse.Namespace) -> GoalView:
    live = not args.json and sys.stdout.isatty()
    return GoalView(sys.stdout, live=live, changes=not args.json and not live)


def _outcome(followed: Followed, args: argparse.Namespace) -> int:
    goal = followed.goal
    if args.json:
        print_json(plain(goal))
        return 0 if goal.state is GoalState.ACHIEVED else 1
    text = f"goal {goal.id} {goal.expression}"
    if followed.timed_out:
        raise DuraError(
            f"{text}: still {goal.state.value} after {args.timeout:g} s (it goes on; "
            f"'dura goal watch {goal.id}' follows it again)"
        )
    if goal.state is not GoalState.ACHIEVED:
        reason = f": {goal.reason}" if goal.reason else ""
        raise DuraError(f"{text}: {goal.state.value}{reason}")
    print(f"{text}: achieved in {_seconds(goal.updated - goal.created)}")
    return 0


def _seconds(value: float) -> str:
    return f"{max(0.0, value):.1f} s"


class Followed:
    """How following a goal ended: the goal as last seen, and whether time ran out."""

    def __init__(self, goal: Goal, timed_out: bool) -> None:
        self.goal = goal
        self.timed_out = timed_out


class GoalView:
    """Shows a followed goal: on a terminal one line, redrawn as it changes (``live``);
    elsewhere a line for each change of its state (``changes``); or nothing."""

    def __init__(self, out: TextIO, *, live: bool, changes: bool) -> None:
        self.out = out
        self.live = live
        self.changes = changes
        self._state: GoalState | None = None
        self._drawn = False

    def show(self, goal: Goal, plan: api.PlanReply | None, now: float) -> None:
        if self.live:
            line = progress(goal, plan, now)
            self.out.write("\r" + line[: _width() - 1] + "\x1b[K")
            self.out.flush()
            self._drawn = True
        elif self.changes and goal.state is not self._state:
            stamp = time.strftime("%H:%M:%S", time.localtime(now))
            reason = f": {goal.reason}" if goal.reason else ""
            self.out.write(f"{stamp}  goal {goal.id} {goal.state.value}{reason}\n")
            self.out.flush()
        self._state = goal.state

    def close(self) -> None:
        """Take the live line away (the outcome is printed in its place)."""
        if self._drawn:
            self.out.write("\r\x1b[K")
            self.out.flush()
            self._drawn = False


def _width() -> int:
    import shutil  # only on a terminal

    return shutil.get_terminal_size().columns


def progress(goal: Goal, plan: api.PlanReply | None, now: float) -> str:
    """One line on how a goal stands: its state, for how long, and the progress of the
    plan that pursues it (steps ended of all, those under way)."""
    line = f"goal {goal.id} {goal.expression}: {goal.state.value}"
    line += f" {_seconds(now - goal.created)}"
    stored = plan.plan if plan is not None else None
    if plan is None or stored is None or goal.id not in stored.goal_ids:
        return line
    if plan.execution.plan != stored.id:
        return line + f"; plan {stored.id} waits"
    steps = plan.execution.steps
    ended = sum(1 for s in steps if s.state == "ended")
    line += f"; plan {stored.id}: {ended} of {len(stored.steps)} steps ended"
    under_way = [f"{s.step} {s.state}" for s in steps if s.state in ACTIVE_STEPS]
    if under_way:
        line += ", " + ", ".join(under_way)
    return line


class GoalFollower:
    """Follows one goal over the bus until it ends.

    It listens to the event log from the start (``GOAL_<STATE>`` events name their
    goal), and looks at the goal again on each event and at least every ``CHECK``
    seconds, so that a missed event delays the outcome but never loses it.
    """

    def __init__(self, bus: Bus) -> None:
        self.bus = bus
        self._woken = threading.Event()
        bus.subscribe(EVENTS, self._on_event)

    def _on_event(self, message: Message) -> None:
        self._woken.set()

    def follow(self, goal: Goal, view: GoalView, timeout: float | None = None) -> Followed:
        """Show the goal as it goes, until it ends or ``timeout`` passes."""
        deadline = None if timeout is None else time.monotonic() + timeout
        try:
            while True:
                self._woken.clear()  # before looking: an event during the look wakes again
                goal = self._look(goal)
                plan = api.PLAN_SHOW.call(self.bus) if view.live else None
                view.show(goal, plan, time.time())
                if not goal.state.is_open:
                    return Followed(goal, timed_out=False)
                left = None if deadline is None else deadline - time.monotonic()
                if left is not None and left <= 0:
                    return Followed(goal, timed_out=True)
                wait = CHECK if left is None else min(CHECK, left)
                self._woken.wait(1.0 if view.live else wait)  # live: the clock moves
                time.sleep(REFRESH)  # a burst of events is one look
        finally:
            view.close()

    def _look(self, goal: Goal) -> Goal:
        """The goal now: among the open goals, or (once it ended) as shown."""
        open_states = [s for s in GoalState if s.is_open]
        query = api.GoalQuery(open_states, before=goal.id + 1, limit=1)  # this goal, if open
        for found in api.GOAL_LIST.call(self.bus, query).goals:
            if found.id == goal.id:
                return found
        return api.GOAL_SHOW.call(self.bus, api.GoalId(goal.id)).goal


def run_list(args: argparse.Namespace) -> int:
    states = [s for s in GoalState if s.is_open] if args.open else None
    first = ask(args, api.GOAL_LIST, api.GoalQuery(states, limit=args.lines))
    goals = first.goals
    left = None if args.lines is None else args.lines - len(goals)
    if first.more and goals and left != 0:  # the older ones, a page at a time
        with connect(args) as bus:
            goals = api.newest_goals(bus, left, states, before=goals[0].id) + goals
    if args.json:
        print_json({"goals": plain(goals)})
    else:
        table(GOAL_HEADERS, goal_rows(goals))
    return 0


def run_show(args: argparse.Namespace) -> int:
    from executive.bus.event_text import describe  # not for 'goal list' (nor 'status')

    reply = ask(args, api.GOAL_SHOW, api.GoalId(args.id))
    if args.json:
        print_json(reply.to_payload())
        return 0
    g = reply.goal
    kind = "maintenance goal" if g.keep else "goal"
    print(f"{kind} {g.id}: {g.expression}")
    state = state_of(g)
    print(f"  state {state}{': ' + g.reason if g.reason else ''}")
    if state in MEANING:
        print(f"  ({MEANING[state].format(updated=clock(g.updated))})")
    deadline = "none" if g.deadline is None else f"{g.deadline:g} s after submission"
    print(f"  priority {g.priority}, deadline {deadline}, from {g.source}")
    print(f"  submitted {clock(g.created)}, last change {clock(g.updated)}")
    if reply.events:
        print()
        table(
            ["time", "event", "details"],
            [[clock(e.stamp), e.kind, describe(e)] for e in reply.events],
        )
    return 0


def run_cancel(args: argparse.Namespace) -> int:
    goal = ask(args, api.GOAL_CANCEL, api.GoalId(args.id)).goal
    if args.json:
        print_json(plain(goal))
    else:
        print(f"goal {goal.id}: {goal.state.value}")
    return 0
