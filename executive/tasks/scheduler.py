"""The scheduler: system configurations for all requests, placed in time, by clingo.

Each call grounds ``schedule.lp`` with the robot's functionalities and the current
requests and solves it with clingo-dl (difference constraints for start times) under
a time limit, keeping the best schedule found. The solver chooses the providers and
the order of the requests that cannot overlap; the start times are then the earliest
that this order, the release times and the start-together groups allow.

A request that cannot be scheduled is cancelled with a reason
(``executive/cancellation.py``).
"""

from __future__ import annotations

import math
import time
from collections.abc import Collection, Iterable, Sequence
from dataclasses import dataclass
from functools import cached_property
from pathlib import Path

import clingo
import networkx as nx
from clingodl import ClingoDLTheory

from executive.tasks.cancellation import explain, precheck
from executive.tasks.schedule import Assignment, Request, ScheduleResult, ScheduleStatus
from knowledge.asp import Answer, Asp, atom
from knowledge.availability import Availability
from knowledge.description import FunctionalitySpec

PROGRAM = Path(__file__).with_name("schedule.lp")
# Core-guided optimisation proves optimality fast; the domain heuristic (schedule
# everything, keep current and best-rated providers, first come first served) makes
# the first model a good one, which matters when the time limit cuts the search.
OPTIONS = ("--opt-strategy=usc", "--opt-usc-shrink=rgs", "--heuristic=Domain", "--models=0")
# With no schedule at the time limit, wait for the first one up to this many limits.
# (Dropping every request is always a schedule; with hundreds of requests the first
# one may take longer than the limit.)
FIRST_SCHEDULE_GRACE = 10
RATING_SCALE = 100  # ratings are floats; the optimisation needs integers
# the optimisation levels of schedule.lp, most important first
COSTS = {
    6: "running_cancelled",  # running tasks that lost their configuration
    5: "changes",  # providers changed in running configurations
    4: "cancelled",  # waiting requests not scheduled
    3: "rating_loss",  # rating given up against the best usable providers (x100)
    2: "serialised",  # pairs of requests that run one after the other
    1: "started",  # functionalities to start that do not run yet
    0: "out_of_order",  # pairs served against first come, first served
}
_EPSILON = 1e-9  # seconds that are a whole number of ticks stay that number


class Scheduler:
    """Schedules requests on a robot's functionalities.

    Args:
        functionalities: the robot's functionalities, with the ratings the knowledge
            base holds (``dataclasses.replace(f, rating=...)``).
        time_limit: seconds one schedule may take, grounding included; the search then
            stops with the best schedule found (or with the first one found later,
            see ``FIRST_SCHEDULE_GRACE``).
        resolution: seconds per tick of the solver's clock.
    """

    def __init__(
        self,
        functionalities: Iterable[FunctionalitySpec],
        *,
        time_limit: float = 1.0,
        resolution: float = 0.1,
    ) -> None:
        self.functionalities = {f.name: f for f in functionalities}
        self.time_limit = time_limit
        self.resolution = resolution

    def schedule(
        self, requests: Sequence[Request], *, faulty: Collection[str] = ()
    ) -> ScheduleResult:
        """Schedule every request it can; cancel the others with a reason.

        Args:
            requests: running tasks and waiting requests, in the order they came.
            faulty: the permanently faulty components.

        Raises:
            ValueError: two requests share an id.
        """
        began = time.perf_counter()
        ids = [r.id for r in requests]
        if len(set(ids)) != len(ids):
            raise ValueError(f"request ids are not unique: {ids}")
        availability = Availability.of(self.functionalities.values(), faulty)
        cancelled = precheck(requests, availability, faulty)
        instance = _Instance.of([r for r in requests if r.id not in cancelled], self.resolution)
        asp = Asp(OPTIONS, theory=ClingoDLTheory())  # type: ignore[no-untyped-call]
        asp.load(PROGRAM)
        asp.add_facts(self._facts(instance, availability))
        asp.ground()
        left = self.time_limit - (time.perf_counter() - began)
        grace = self.time_limit * (FIRST_SCHEDULE_GRACE - 1)
        outcome = asp.solve(timeout=max(left, 0.0), grace=grace, keep=False, costs=True)
        if not outcome.answers:
            return ScheduleResult(
                ScheduleStatus.TIMEOUT, cancelled=cancelled, solve_time=time.perf_counter() - began
            )
        answer = outcome.answers[-1]
        scheduled = {instance.name(t) for (t,) in answer.get("scheduled")}
        assignments = _assignments(instance, answer, scheduled)
        left_out = sorted(instance.requests.keys() - scheduled, key=ids.index)
        cancelled.update(explain(left_out, instance.requests, assignments, availability))
        cost = dict.fromkeys(COSTS.values(), 0)
        cost.update((COSTS[p], c) for p, c in zip(answer.priority, answer.cost, strict=True))
        return ScheduleResult(
            ScheduleStatus.OPTIMAL if outcome.exhausted else ScheduleStatus.FEASIBLE,
            assignments=assignments,
            cancelled={i: cancelled[i] for i in ids if i in cancelled},
            cost=cost,
            solve_time=time.perf_counter() - began,
        )

    def _facts(self, instance: _Instance, availability: Availability) -> list[clingo.Symbol]:
        out: list[clingo.Symbol] = []
        for f in self.functionalities.values():
            out += [
                atom("functionality", f.name),
                atom("rating", f.name, round(f.rating * RATING_SCALE)),
            ]
            out += [atom("provides", f.name, c) for c in f.provides]
            out += [atom("requires", f.name, c) for c in f.requires]
            out += [atom("exclusive", f.name)] if not f.shareable else []
            out += [atom("usable", f.name)] if f.name in availability.usable else []
        # first come, first served: by release time, then by arrival
        arrival = {t: i for i, t in enumerate(instance.requests)}
        ranked = sorted(arrival, key=lambda t: (instance.release[t], arrival[t]))
        active: set[str] = set()
        for rank, name in enumerate(ranked):
            r, t = instance.requests[name], instance.number[name]
            out += [
                atom("request", t),
                atom("behavior", t, r.behavior),
                atom("rank", t, rank),
                atom("duration", t, instance.duration[name]),
                atom("release", t, instance.release[name]),
            ]
            out += [atom("needs", t, c) for c in r.needs]
            # a partner not among them (never here: the precheck cancels its group) is a
            # number no request has, which is never scheduled
            together = [instance.number.get(u, len(instance.requests)) for u in r.together]
            out += [atom("together", t, u) for u in together]
            out += [atom("together", u, t) for u in together]
            if name in instance.deadline:
                out.append(atom("deadline", t, instance.deadline[name]))
            if r.running:
                out.append(atom("running", t))
                out += [atom("current", t, c, f) for c, f in r.configuration.items()]
                active.update(r.configuration.values())
        out += [atom("active", f) for f in sorted(active)]
        return out


@dataclass(frozen=True)
class _Instance:
    """The requests the solver sees, their times in ticks. The solver knows a request
    by its number (its place among them), not by its id: clingo keeps every symbol it
    ever made for the life of the process, and numbers that come back in every schedule
    make no new ones, where every task's own id would grow the executive by kilobytes."""

    tick: float
    requests: dict[str, Request]
    duration: dict[str, int]
    release: dict[str, int]
    deadline: dict[str, int]  # waiting requests only: a running task just runs

    @cached_property
    def number(self) -> dict[str, int]:
        """The solver's number of each request."""
        return {name: n for n, name in enumerate(self.requests)}

    @cached_property
    def _names(self) -> list[str]:
        return list(self.requests)

    def name(self, number: object) -> str:
        """The request the solver's number stands for."""
        return self._names[int(str(number))]

    @classmethod
    def of(cls, requests: Sequence[Request], tick: float) -> _Instance:
        return cls(
            tick=tick,
            requests={r.id: r for r in requests},
            duration={r.id: max(1, math.ceil(r.duration / tick - _EPSILON)) for r in requests},
            release={
                r.id: 0 if r.running else math.ceil(r.earliest / tick - _EPSILON) for r in requests
            },
            deadline={
                r.id: math.floor(r.deadline / tick + _EPSILON)
                for r in requests
                if r.deadline is not None and not r.running
            },
        )


def _assignments(instance: _Instance, answer: Answer, scheduled: set[str]) -> dict[str, Assignment]:
    """The earliest starts that respect the chosen order, release times and groups.

    Start-together groups move as one; the order between groups has no cycle (the
    solver's difference constraints would have failed), so one pass in topological
    order gives the least solution, which meets every deadline the solver met.
    """
    groups: nx.Graph = nx.Graph()
    groups.add_nodes_from(scheduled)
    groups.add_edges_from((t, u) for t in scheduled for u in instance.requests[t].together)
    members = [sorted(group) for group in nx.connected_components(groups)]
    group_of = {t: i for i, group in enumerate(members) for t in group}
    after: dict[str, set[str]] = {t: set() for t in scheduled}
    order: nx.DiGraph = nx.DiGraph()
    order.add_nodes_from(range(len(members)))
    for numbers in answer.get("before"):
        first, then = (instance.name(n) for n in numbers)
        after[then].add(first)
        order.add_edge(group_of[first], group_of[then])
    start: dict[int, int] = {}
    for group in nx.topological_sort(order):
        start[group] = max(
            [instance.release[t] for t in members[group]]
            + [start[group_of[p]] + instance.duration[p] for t in members[group] for p in after[t]]
        )
    providers: dict[str, dict[str, str]] = {t: {} for t in scheduled}
    for t, c, f in answer.get("use"):
        providers[instance.name(t)][str(c)] = str(f)
    arrival = {t: i for i, t in enumerate(instance.requests)}
    out = []
    for t in scheduled:
        begin = round(start[group_of[t]] * instance.tick, 9)
        out.append(
            Assignment(
                request=t,
                start=begin,
                end=begin + instance.requests[t].duration,
                providers=dict(sorted(providers[t].items())),
                after=frozenset(after[t]),
            )
        )
    out.sort(key=lambda a: (a.start, arrival[a.request]))
    return {a.request: a for a in out}
