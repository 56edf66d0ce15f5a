"""The task executor's decisions: from the tasks and the faults to a schedule and the
configuration changes that carry it out.

:func:`decide` is a pure function: it reads the tasks (as :class:`TaskView`), the
running system configuration, the permanently faulty components and the ratings the
knowledge base holds, and the time; it starts no process, sends nothing on the bus and
writes nothing. The scheduler (clingo) places every waiting and running task; the
decision says which waiting tasks start now (and on which providers), which start
later (and when to decide again), which wait for a running task to end, which the
scheduler cancelled (and why), which running tasks change providers, and the
configuration to run with the steps from the running one. The executor
(:mod:`executive.tasks.enactment`) carries the decision out.

:func:`keep_running` then keeps functionalities running that no task holds any more but
that are still wanted: those the plan's upcoming steps need (consecutive steps on the
same functionalities do not stop and start them in between), and those that linger
for a while after their last task. It keeps only what runs already and is usable; it
never starts anything.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Collection, Iterable, Mapping, Sequence
from dataclasses import dataclass, field

from executive.tasks.configuration import SystemConfiguration, Transition
from executive.tasks.schedule import Request, ScheduleResult
from executive.tasks.scheduler import Scheduler
from executive.tasks.task import TaskView
from knowledge.description import FunctionalitySpec, RobotDescription

NOW = 0.15  # a task scheduled to start within this many seconds starts now
RESOLUTION = 0.1  # seconds: the scheduler's clock, and the least time a running task has left
DEADLINE_FLOOR = 1e-3  # seconds: a deadline that has passed still reaches the scheduler as one


@dataclass(frozen=True)
class Decision:
    """What one round of scheduling decided.

    Args:
        schedule: the scheduler's result (``None``: no task waits or runs).
        cancelled: waiting or running tasks the scheduler cancelled, with its reason.
        reconfigured: running tasks whose providers change, with their new providers.
        start_now: waiting tasks that start now, with their providers.
        start_later: waiting tasks that start later, with their start (epoch seconds).
        behind_running: waiting tasks that start when a running task ends (it may
            overrun, so they get no time).
        behind: for each of those, the running tasks it waits for.
        configuration: the system configuration to run after the decision.
        transition: the steps from the running configuration to that one.
    """

    schedule: ScheduleResult | None = None
    cancelled: Mapping[str, str] = field(default_factory=dict)
    reconfigured: Mapping[str, Mapping[str, str]] = field(default_factory=dict)
    start_now: Mapping[str, Mapping[str, str]] = field(default_factory=dict)
    start_later: Mapping[str, float] = field(default_factory=dict)
    behind_running: frozenset[str] = frozenset()
    behind: Mapping[str, tuple[str, ...]] = field(default_factory=dict)
    configuration: SystemConfiguration = field(default_factory=SystemConfiguration)
    transition: Transition = field(default_factory=Transition)

    @property
    def wake(self) -> float | None:
        """When to decide again (epoch seconds): the earliest later start."""
        return min(self.start_later.values(), default=None)


def decide(
    tasks: Sequence[TaskView],
    running: SystemConfiguration,
    *,
    robot: RobotDescription,
    faulty: Collection[str],
    ratings: Mapping[str, float],
    now: float,
    time_limit: float = 1.0,
) -> Decision:
    """Schedule the waiting and running tasks and decide what changes.

    Args:
        tasks: every task the executor knows, ended ones included (a start-together
            partner that ended cannot start with anyone; one never asked for is
            ignored).
        running: the system configuration that runs now.
        robot: the robot description.
        faulty: the permanently faulty components.
        ratings: functionality ratings the knowledge base holds (the description's
            rating where it holds none).
        now: the time (epoch seconds) the decision is for.
        time_limit: seconds the scheduler may take.
    """
    functionalities = [
        dataclasses.replace(f, rating=ratings.get(f.name, f.rating))
        for f in robot.functionalities.values()
    ]
    live = [t for t in tasks if not t.phase.final]  # waiting, or holding a configuration
    if not live:
        return _changes(Decision(), running, SystemConfiguration(), functionalities)
    known = {t.id for t in tasks}
    requests = [_request(t, robot, known, now) for t in live]
    result = Scheduler(functionalities, time_limit=time_limit).schedule(
        requests, faulty=frozenset(faulty)
    )
    by_id = {t.id: t for t in live}
    reconfigured: dict[str, Mapping[str, str]] = {}
    start_now: dict[str, Mapping[str, str]] = {}
    start_later: dict[str, float] = {}
    behind: dict[str, tuple[str, ...]] = {}
    for task_id, assignment in result.assignments.items():
        task, providers = by_id[task_id], dict(assignment.providers)
        if task.phase.holds:
            if providers != dict(task.providers):
                reconfigured[task_id] = providers
        elif any(a in by_id and by_id[a].phase.holds for a in assignment.after):
            behind[task_id] = tuple(
                a for a in assignment.after if a in by_id and by_id[a].phase.holds
            )
        elif assignment.start <= NOW:
            start_now[task_id] = providers
        else:
            start_later[task_id] = now + assignment.start
    holding = {
        t.id: reconfigured.get(t.id, t.providers)
        for t in live
        if t.phase.holds and t.id not in result.cancelled
    }
    target = SystemConfiguration({**holding, **start_now})
    decision = Decision(
        schedule=result,
        cancelled=dict(result.cancelled),
        reconfigured=reconfigured,
        start_now=start_now,
        start_later=start_later,
        behind_running=frozenset(behind),
        behind=behind,
    )
    return _changes(decision, running, target, functionalities)


def _request(
    task: TaskView, robot: RobotDescription, known: Collection[str], now: float
) -> Request:
    """The scheduler's request for a task, its times relative to ``now``."""
    needs = robot.behaviors[task.behavior].requires
    if task.phase.holds:
        ran = now - task.began if task.began is not None else 0.0
        return Request(
            task.id,
            task.behavior,
            needs,
            max(RESOLUTION, task.duration - ran),
            running=True,
            configuration=dict(task.providers),
        )
    deadline = None if task.deadline is None else max(DEADLINE_FLOOR, task.deadline - now)
    return Request(
        task.id,
        task.behavior,
        needs,
        task.duration,
        max(0.0, task.earliest - now),
        deadline,
        tuple(t for t in task.together if t in known),
    )


def _changes(
    decision: Decision,
    running: SystemConfiguration,
    target: SystemConfiguration,
    functionalities: Sequence[FunctionalitySpec],
) -> Decision:
    return dataclasses.replace(
        decision, configuration=target, transition=running.transition(target, functionalities)
    )


def keep_running(
    decision: Decision,
    running: SystemConfiguration,
    *,
    robot: RobotDescription,
    faulty: Collection[str],
    upcoming: Sequence[str] = (),
    lingering: Iterable[str] = (),
    standby: bool = True,
) -> Decision:
    """The decision with functionalities kept running that no task holds now.

    Args:
        decision: what the scheduling decided (its configuration holds the tasks).
        running: the configuration that runs now.
        faulty: the permanently faulty components (never kept).
        upcoming: the behaviors of the plan's steps still to come, in order.
        lingering: functionalities that linger after their last task.
        standby: keep the warm spares (functionalities with ``standby: true``) and
            what they run on, started if need be.
    """
    target = decision.configuration
    offered: dict[str, str] = {}  # capability -> a running functionality providing it
    for _, providers in (*target.holders(), *running.holders()):
        for capability, f in providers.items():
            offered.setdefault(capability, f)
    reserved: dict[str, Mapping[str, str]] = {}
    for i, behavior in enumerate(upcoming):
        needs = robot.behaviors[behavior].requires if behavior in robot.behaviors else ()
        wanted = _closure(needs, offered, robot, faulty)
        if wanted:
            reserved[f"upcoming step {i + 1}: {behavior}"] = wanted
    for f in sorted(lingering):
        spec = robot.functionalities.get(f)
        if spec is None or f not in running.functionalities:
            continue
        below = _closure(spec.requires, offered, robot, faulty)
        if below is not None and f not in faulty:
            reserved[f"lingering: {f}"] = {**below, (spec.provides or (f,))[0]: f}
    spares: dict[str, Mapping[str, str]] = {}
    for spec in robot.functionalities.values() if standby else ():
        if spec.standby:
            wanted = _spare(spec, offered, robot, faulty)
            if wanted is not None:
                spares[f"standby: {spec.name}"] = wanted
    configuration = SystemConfiguration(target.tasks, reserved, spares)
    functionalities = list(robot.functionalities.values())
    return _changes(decision, running, configuration, functionalities)


def _spare(
    spec: FunctionalitySpec,
    offered: Mapping[str, str],
    robot: RobotDescription,
    faulty: Collection[str],
) -> dict[str, str] | None:
    """A spare and the providers it runs on: what runs where it can, else the best-rated
    usable provider; ``None`` if it cannot run."""
    if spec.name in faulty:
        return None
    providers = {(spec.provides or (spec.name,))[0]: spec.name}
    chosen = _choose(spec.requires, offered, robot, faulty, frozenset({spec.name}))
    return None if chosen is None else {**providers, **chosen}


def _choose(
    needs: Iterable[str],
    offered: Mapping[str, str],
    robot: RobotDescription,
    faulty: Collection[str],
    visiting: frozenset[str],
) -> dict[str, str] | None:
    """Usable providers for ``needs`` and what they require, preferring what runs."""
    out: dict[str, str] = {}
    for capability in needs:
        candidates = sorted(
            (f for f in robot.functionalities.values() if capability in f.provides),
            key=lambda f: (f.name != offered.get(capability), -f.rating, f.name),
        )
        for f in candidates:
            if f.name in faulty or f.name in visiting:
                continue
            below = _choose(f.requires, offered, robot, faulty, visiting | {f.name})
            if below is not None:
                out.update({capability: f.name, **below})
                break
        else:
            return None
    return out


def _closure(
    needs: Iterable[str],
    offered: Mapping[str, str],
    robot: RobotDescription,
    faulty: Collection[str],
) -> dict[str, str] | None:
    """Providers of ``needs`` and of what they require in turn, all from ``offered`` and
    none faulty; ``None`` if ``offered`` does not cover them."""
    providers: dict[str, str] = {}
    todo = list(needs)
    while todo:
        capability = todo.pop()
        if capability in providers:
            continue
        f = offered.get(capability)
        if f is None or f in faulty or f not in robot.functionalities:
            return None
        providers[capability] = f
        todo.extend(robot.functionalities[f].requires)
    return providers
