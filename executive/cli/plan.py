"""``dura plan --offline DOMAIN PROBLEM``: plan without a robot, for domain authors;
``dura plan show``: the running robot's current plan as a timeline; ``dura plan
--dry-run``: what the running robot's planner would do now, without doing it."""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path
from typing import Any

from executive.bus.api import planning as api
from executive.bus.api import tasks
from executive.bus.schema import plain
from executive.bus.wording import goals_named, plural
from executive.cli.arguments import seconds
from executive.cli.client import add_client_options, ask, connect
from executive.cli.output import add_json_flag, bar, print_json, shown, table
from executive.cli.progress import LiveLine
from executive.dashboard import gantt
from executive.fast_start import use_reader_environment
from executive.planning.dry_run import planned_steps
from executive.planning.expression import TRUE, Expression
from executive.planning.goals import GoalSpec
from executive.planning.metric import Metric
from executive.planning.partial_order import PartialOrderPlan, Step
from executive.planning.planner import Planner, PlanningTask, PlanResult, choices
from executive.planning.portfolio import Portfolio
from executive.planning.problem import World, build, read_problem
from knowledge.description import DEFAULT_ENGINE, PORTFOLIO
from knowledge.domain import parse
from knowledge.errors import DomainError, DuraError


def register(sub: Any) -> None:
    p = sub.add_parser(
        "plan",
        help="show the running robot's plan (show), plan for its open goals without executing "
        "(--dry-run), or plan without a robot (--offline)",
        description="'dura plan show' prints the running robot's current plan as a timeline, "
        "with the state of each step. 'dura plan --dry-run' plans for the running robot's open "
        "goals (and each --goal, as if it were added now) from its live state and prints the "
        "plan, without executing it or changing anything: exit 0 with a plan (or nothing to "
        "plan), 1 without one. 'dura plan "
        "--offline DOMAIN PROBLEM' plans for the goal of a PDDL problem with one of dura's "
        "engines, validates the plan, and prints it as a timeline: exit 0 with a plan, 1 "
        "without one.",
    )
    p.add_argument("show", nargs="?", choices=["show"], help="the running robot's current plan")
    p.add_argument(
        "--offline",
        nargs=2,
        metavar=("DOMAIN", "PROBLEM"),
        type=Path,
        help="the domain and problem PDDL files",
    )
    p.add_argument(
        "--dry-run",
        action="store_true",
        help="plan for the running robot's open goals on its live state, without executing",
    )
    p.add_argument(
        "--goal",
        action="append",
        default=[],
        metavar="EXPR",
        help="with --dry-run: also plan for this goal, as if it were added now (nothing is "
        "added; repeatable)",
    )
    p.add_argument(
        "--engine",
        default=DEFAULT_ENGINE,
        choices=choices(),
        help=f"the planning engine (default {DEFAULT_ENGINE}: the first installed engine that "
        f"supports the problem; {PORTFOLIO}: every installed engine at once, the first plan, "
        "or the shortest by the timeout when the problem minimises the makespan)",
    )
    p.add_argument(
        "--timeout",
        type=seconds(),
        metavar="S",
        help="seconds to search (offline: 30; dry run: the robot's planner timeout)",
    )
    p.add_argument(
        "--svg",
        metavar="FILE",
        help="also draw the plan as a Gantt chart into an SVG file ('-': stdout, nothing else); "
        "with 'show', each step's progress, task and configuration and the replans before it",
    )
    add_client_options(p)
    add_json_flag(p)
    p.set_defaults(run=run, parser=p)


def run(args: argparse.Namespace) -> int:
    if [args.show is not None, args.offline is not None, args.dry_run].count(True) != 1:
        args.parser.error("say one of 'show', '--dry-run' or '--offline DOMAIN PROBLEM'")
    if args.goal and not args.dry_run:
        args.parser.error("--goal goes with --dry-run")
    if args.show:
        return run_show(args)
    if args.dry_run:
        return run_dry_run(args)
    domain, problem = args.offline
    use_reader_environment()  # this process reads the PDDL; its planner worker plans
    timeout = args.timeout or 30.0
    chosen = Portfolio((), timeout) if args.engine == PORTFOLIO else Planner(args.engine, timeout)
    with LiveLine(shown=not args.json) as line, chosen as planner:
        if not isinstance(planner, Portfolio):
            planner.start()  # the worker loads unified-planning while this process reads
        line.doing(f"reading {shown(domain)} and {shown(problem)}")
        world, goal, metric = fitting_world(domain, problem)
        line.clear()
        if goal == TRUE and not args.json:
            print(f"dura: warning: {shown(problem)} has an empty goal, so any plan is empty: "
                  "write one in its (:goal ...)", file=sys.stderr)  # fmt: skip
        task = PlanningTask(domain.resolve(), world, (GoalSpec(0, goal),), metric=metric)
        line.doing(f"starting the planner ({args.engine}) and reading the domain")
        planner.start(domain.resolve())
        line.doing(f"planning with {args.engine} (at most {timeout:g} s)")
        result = planner.solve(task)
        line.doing("stopping the planner")
    if args.svg is not None and result.plan is not None:
        title = f"{problem.name}: {plural(len(result.plan.steps), 'step')}, makespan {result.plan.makespan:g} s, by {result.engine}"
        if write_svg(args.svg, gantt.render(gantt.offline_gantt(result.plan, title))):
            return 0
    if args.json:
        print_json(as_json(result))
        return 0 if result.ok else 1
    if not result.ok or result.plan is None:
        print(f"dura: {shown(problem)}: no plan: {result.reason}", file=sys.stderr)
        return 1
    for note in result.notes:
        print(f"dura: note: {note}", file=sys.stderr)
    print(
        f"{shown(problem)}: {plural(len(result.plan.steps), 'step')}, makespan {result.plan.makespan:g} s, "
        f"by {result.engine} in {result.time:.2f} s, validated by {result.validator}"
    )
    print_timeline(result.plan)
    return 0


def fitting_world(domain: Path, problem: Path) -> tuple[World, Expression, Metric | None]:
    """The world, goal and metric of a problem file, checked to fit the domain before any engine
    runs: a problem that does not fit is the user's error, not an engine's failure.

    Raises:
        DomainError: the domain or the problem is invalid, or they do not fit.
    """
    lifted = parse(domain)
    world, goal, metric = read_problem(domain, problem, lifted)
    try:
        build(lifted, world, (GoalSpec(0, goal),), metric=metric)
    except DomainError as e:
        raise DomainError(f"{shown(problem)}: does not fit {shown(domain)}: {e}") from e
    return world, goal, metric


def run_show(args: argparse.Namespace) -> int:
    reply = ask(args, api.PLAN_SHOW)
    if args.svg is not None and reply.plan is None:
        raise DuraError("no plan yet: no picture written")
    if args.svg is not None and reply.plan is not None:
        with connect(args) as bus:
            events = api.newest_events(bus, 2000)
        # a fleet's tasks are its robots': it has none of its own
        found = ask(args, tasks.TASK_LIST).tasks if reply.robots is None else []
        chart = gantt.live_gantt(
            reply.plan, reply.execution, events, found, time.time(), robots=reply.robots
        )
        if write_svg(args.svg, gantt.render(chart)):
            return 0
    if args.json:
        print_json(reply.to_payload())
        return 0
    plan = reply.plan
    if plan is None:
        print("no plan yet")
        return 0
    states = reply.execution.states_of(plan)
    steps = plan.steps
    span = max((s.start + (s.duration or 0.0) for s in steps), default=0.0)
    print(f"plan {plan.id}: {plan.state.value}, by {plan.engine}, for {goals_named(plan.goal_ids)}")
    rows = [
        [s.index, f"{s.start:.3f}", _duration(s.duration), f"{s.action}({', '.join(s.args)})",
         states.get(s.index, "-"), bar(s.start, s.duration, span)]
        for s in steps
    ]  # fmt: skip
    headers = ["#", "start", "duration", "step", "state", "timeline"]
    if reply.robots is not None:  # a fleet's plan: who carries out each step
        robots = [*reply.robots, *[""] * len(rows)][: len(rows)]
        rows = [[*row[:1], robot or "-", *row[1:]] for row, robot in zip(rows, robots, strict=True)]
        headers.insert(1, "robot")
    table(headers, rows)
    return 0


def run_dry_run(args: argparse.Namespace) -> int:
    wait = max(api.PLAN_DRY_RUN.timeout, 3 * (args.timeout or 0.0) + 30.0)
    reply = ask(args, api.PLAN_DRY_RUN, api.DryRun(args.timeout, args.goal), timeout=wait)
    ok = reply.status in ("solved", "nothing_to_do")
    if args.json:
        print_json(reply.to_payload())
        return 0 if ok else 1

    def named(goal: int) -> str:
        """A stored goal by its id, a goal asked about (id -n) by its expression."""
        return f"goal {goal}" if goal > 0 else reply.asked[-goal - 1]

    for held in reply.achieved:
        print(f"{named(held)}: holds already")
    for key, why in sorted(reply.unreachable.items(), key=lambda kv: int(kv[0])):
        print(f"{named(int(key))}: unreachable: {why}")
    if reply.status == "nothing_to_do":
        print(f"dry run: nothing to plan ({reply.reason})")
        return 0
    if not ok:
        print(f"dura: dry run: no plan: {reply.reason}", file=sys.stderr)
        return 1
    stored = [g for g in reply.planned if g > 0]
    asked = [named(g) for g in reply.planned if g < 0]
    goals = ", ".join(([goals_named(stored)] if stored else []) + asked) or "no goal"
    print(
        f"dry run: {plural(len(reply.steps), 'step')}, makespan {reply.makespan or 0.0:g} s, by "
        f"{reply.engine} in {reply.time:.2f} s, for {goals} (nothing executed)"
    )
    span = reply.makespan or 0.0
    rows = [
        [s.index, f"{s.start:.3f}", _duration(s.duration), f"{s.action}({', '.join(s.args)})",
         " ".join(f"{p.step}{'' if p.at == 'end' else '(start)'}" for p in s.after) or "-",
         bar(s.start, s.duration, span)]
        for s in reply.steps
    ]  # fmt: skip
    table(["#", "start", "duration", "step", "after", "timeline"], rows)
    return 0


def write_svg(target: str, picture: str) -> bool:
    """Write a picture to a file, or to stdout for '-'; whether stdout took it (then
    nothing else is printed)."""
    if target == "-":
        sys.stdout.write(picture)
        return True
    Path(target).write_text(picture, encoding="utf-8")
    print(f"{shown(target)}: the plan as a Gantt chart", file=sys.stderr)
    return False


def _duration(duration: float | None) -> str:
    return "-" if duration is None else f"{duration:g}"


def _after(step: Step) -> str:
    return (
        " ".join(f"{p.step}{'' if p.at.value == 'end' else '(start)'}" for p in step.after) or "-"
    )


def print_timeline(plan: PartialOrderPlan) -> None:
    """The steps as a table with a bar for each, scaled to the makespan."""
    rows = [
        [s.index, f"{s.start:.3f}", _duration(s.duration), s.label, _after(s),
         bar(s.start, s.duration, plan.makespan)]
        for s in plan.steps
    ]  # fmt: skip
    table(["#", "start", "duration", "step", "after", "timeline"], rows)


def as_json(result: PlanResult) -> dict[str, Any]:
    plan = result.plan
    return {
        "status": result.status.value,
        "engine": result.engine,
        "time": round(result.time, 4),
        "validator": result.validator,
        "reason": result.reason,
        "makespan": plan.makespan if plan is not None else None,
        "steps": plain(planned_steps(plan)),
        "log": list(result.log),
        "notes": list(result.notes),
    }
