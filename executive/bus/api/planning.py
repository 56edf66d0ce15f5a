"""The high level's API: goals, plans, the world's facts and objects, the domain, events,
status.

The replies carry typed records: the knowledge base's (:class:`~knowledge.records.Goal`,
:class:`~knowledge.records.Plan`, :class:`~knowledge.records.Event`,
:class:`~knowledge.records.Fact`, :class:`~knowledge.records.ComponentRecord`), what the
services report (:mod:`executive.bus.reports`: the execution, the goal planner, tasks,
components) and those declared here: a planned step (:class:`PlannedStep`) and the
domain (:class:`DomainType`, :class:`DomainSignature`, :class:`DomainAction`).
"""

from __future__ import annotations

from dataclasses import field
from typing import TYPE_CHECKING, Annotated

from executive.bus.api.free_form import GoalFields
from executive.bus.keys import api
from executive.bus.reports import (
    ComponentEntry,
    DiagnosisInfo,
    ExecutionStatus,
    ExecutorTask,
    PlannerStatus,
)
from executive.bus.schema import Between, Payload, Text
from executive.bus.verb import Empty, Verb
from knowledge.conventions import Above, AtMost
from knowledge.record_class import record
from knowledge.records import ComponentRecord, Event, Fact, Goal, KeyAccess, Plan, TimedFact
from knowledge.transitions import GoalState

if TYPE_CHECKING:
    from executive.bus.session import Bus

Count = Annotated[int, Between(0, 2**63 - 1)]
LIMIT = 10**9  # no count, priority or number of seconds a person means is larger
Priority = Annotated[int, Between(-LIMIT, LIMIT)]  # what the CLI accepts too
Deadline = Annotated[float, Above(0.0), AtMost(LIMIT)]  # seconds from now, as the CLI's


@record
class StepAfter:
    """What a planned step waits for: the start or the end (``at``) of another step."""

    step: int
    at: str


@record
class PlannedStep:
    """A step of a plan just found, as ``dura plan --offline --json`` prints it: when it
    starts (seconds from the plan's start), for how long, and the steps it comes after."""

    index: int
    action: str
    args: tuple[str, ...]
    start: float
    duration: float | None
    after: tuple[StepAfter, ...] = ()


@record
class DomainType:
    """A type of the domain and its parent (``object`` at the top)."""

    name: str
    parent: str


@record
class DomainSignature:
    """A predicate or function of the domain and the types of its parameters."""

    name: str
    parameters: tuple[str, ...]


@record
class DomainAction:
    """An action of the domain: its parameters (``?name``, type), whether it is durative,
    its duration as written, and the task that carries it out (its behavior and the
    behavior's goal fields: ``?parameter`` or a constant); ``blocked``: why it cannot run
    now (permanently faulty components), or ``None`` (offline: not known)."""

    name: str
    parameters: tuple[tuple[str, str], ...]
    durative: bool
    duration: str | None
    task: str | None
    behavior: str | None
    goal: GoalFields
    blocked: str | None


@record
class Unanswered:
    """A section of ``status`` that another service adds, when it did not answer: why."""

    error: str


@record
class FleetRobot:
    """One robot of a fleet as its high level sees it: whether it can act now, and why
    not (``status`` of ``dura fleet run``)."""

    robot: str
    available: bool
    reason: str = ""


@record
class GoalAdd(Payload):
    """A goal expression with its priority, deadline (seconds from now) and source;
    ``keep``: a maintenance goal, re-posted whenever it stops holding."""

    expression: Text
    priority: Priority = 0
    deadline: Deadline | None = None
    source: str = "user"
    keep: bool = False


@record
class GoalId(Payload):
    """A goal, by id."""

    id: int


@record
class GoalQuery(Payload):
    """Goals in these states (all states without) and before a goal id (unless
    ``before`` is 0), oldest first: all of them, or the newest ``limit``. A reply carries
    the newest of them that fit under the bus's payload limit (:class:`GoalsReply`
    ``more``); :func:`newest_goals` pages through them all."""

    states: list[GoalState] | None = None
    before: Count = 0
    limit: Count | None = None


@record
class GoalReply(Payload):
    """A goal as stored."""

    goal: Goal


@record
class GoalsReply(Payload):
    """Goals as stored, by id. ``more``: some of those asked for were left out to keep
    the reply under the bus's payload limit (the oldest of them): ask again before the
    first one (``before``). Sent only when true, so that other replies are unchanged on
    the wire."""

    goals: list[Goal]
    more: bool | None = None


@record
class GoalHistory(Payload):
    """A goal and the events that name it."""

    goal: Goal
    events: list[Event]


@record
class PlanReply(Payload):
    """The newest plan (stored) and how its execution stands; for a fleet's plan,
    ``robots``: the robot that carries out each step, in the order of the plan's steps
    ("" for a step no robot carries out; not sent for a robot's own plan)."""

    plan: Plan | None
    execution: ExecutionStatus
    robots: list[str] | None = None


@record
class DryRun(Payload):
    """Plan for the open goals, and the goal expressions ``goals`` as if they were added
    now, on the live state without executing (seconds to search; the robot's planner
    timeout without)."""

    timeout: Annotated[float, Between(0.1, 3600.0)] | None = None
    goals: list[Text] = field(default_factory=list)


@record
class DryRunReply(Payload):
    """What the planner would do now: the plan for the goals it reaches (``steps`` as
    ``dura plan --offline --json`` prints them), the goals that hold already, and why
    each other goal is unreachable, by id: a stored goal's id, and for the n-th goal
    expression asked about (``asked``, not stored) the id -n."""

    status: str
    engine: str
    time: float
    reason: str
    goals: list[int]
    planned: list[int]
    achieved: list[int]
    unreachable: dict[str, str]
    steps: list[PlannedStep]
    makespan: float | None = None
    asked: list[str] = field(default_factory=list)


@record
class StateQuery(Payload):
    """Facts matching ``robot_at``, ``(robot_at lab)``, ``(robot_at *)`` (all without)."""

    pattern: str = ""


@record
class StateReply(Payload):
    """Facts and objects (name -> type), and the facts that take effect later (not sent
    when there are none)."""

    facts: list[Fact]
    objects: dict[str, str]
    timed: list[TimedFact] | None = None


@record
class FactChange(Payload):
    """A fact to set or unset: ``(robot_at lab)``, ``(= (battery) 80)``; ``source`` names
    who changes it (a component's name, or ``user``), as the event log records it;
    ``at``: when it takes effect (wall clock, seconds since the epoch; now if not set)."""

    fact: Text
    source: Text = "user"
    at: float | None = None


@record
class FactReply(Payload):
    """The fact as it was set or unset (``at``: when it takes effect, if later)."""

    fact: Fact
    at: float | None = None


@record
class ObjectAdd(Payload):
    """An object of a domain type."""

    name: Text
    type: Text


@record
class ObjectName(Payload):
    """An object of the world, by name."""

    name: Text


@record
class DomainReply(Payload):
    """The robot's domain: its types, predicates, functions and actions, and its
    constants by name, with their types."""

    name: str
    path: str
    types: list[DomainType]
    predicates: list[DomainSignature]
    functions: list[DomainSignature]
    actions: list[DomainAction]
    constants: dict[str, str]


@record
class EventQuery(Payload):
    """Events after a sequence number (and before one, unless ``before`` is 0), of one
    kind (all without), oldest first: the newest ``limit`` of them, or with ``oldest``
    the oldest ``limit`` (to page forward through the log without a gap)."""

    after: Count = 0
    limit: Count = 100
    kind: str | None = None
    oldest: bool = False
    before: Count = 0


@record
class EventsReply(Payload):
    """Events of the log, oldest first. ``more``: some of those asked for were left
    out to keep the reply under the bus's payload limit (the oldest of them, or with
    ``oldest`` the newest): ask again before the first one (``before``), or after the
    last one (``after``). :func:`newest_events` does it. Sent only when true, so that
    other replies are unchanged on the wire."""

    events: list[Event]
    more: bool | None = None


@record
class NoDiagnosis:
    """No diagnosis result yet: ``{}`` where ``status`` has one."""


@record
class StatusReply(KeyAccess, Payload):
    """Everything at a glance. ``goals``: the open goals and the newest
    :data:`RECENT_GOALS` others (a long run's goals are many: ``goal/list`` pages through
    them all); ``goal_counts``: how many goals are in each state (not sent by an executive
    before 0.2). ``diagnoses`` is the newest diagnosis result, if any.
    ``tasks`` and ``components`` come from the task executor and the launcher, or say
    why that service did not answer; ``robots``, for a fleet, from its links. ``planning`` says whether the goal planner is
    computing a plan, since when and why."""

    robot: str
    goals: list[Goal]
    plan: Plan | None
    execution: ExecutionStatus
    diagnoses: DiagnosisInfo | NoDiagnosis
    faults: list[ComponentRecord]
    tasks: list[ExecutorTask] | Unanswered | None = None
    components: list[ComponentEntry] | Unanswered | None = None
    planning: PlannerStatus | None = None
    robots: list[FleetRobot] | Unanswered | None = None  # a fleet's robots
    goal_counts: dict[str, int] | None = None  # goals in each state, all of them

    @property
    def diagnosis(self) -> DiagnosisInfo | None:
        """The newest diagnosis result, or ``None`` before the first."""
        return self.diagnoses if isinstance(self.diagnoses, DiagnosisInfo) else None


RECENT_GOALS = 20  # the ended goals ``status`` carries besides the open ones

GOAL_ADD = Verb(api("goal/add"), GoalAdd, GoalReply)
GOAL_LIST = Verb(api("goal/list"), GoalQuery, GoalsReply)
GOAL_SHOW = Verb(api("goal/show"), GoalId, GoalHistory)
GOAL_CANCEL = Verb(api("goal/cancel"), GoalId, GoalReply)
PLAN_SHOW = Verb(api("plan/show"), Empty, PlanReply)
PLAN_DRY_RUN = Verb(api("plan/dry-run"), DryRun, DryRunReply, timeout=120.0)
STATE_GET = Verb(api("state/get"), StateQuery, StateReply)
STATE_SET = Verb(api("state/set"), FactChange, FactReply)
STATE_UNSET = Verb(api("state/unset"), FactChange, FactReply)
OBJECT_ADD = Verb(api("object/add"), ObjectAdd, ObjectAdd)
# what left the world with the object: the object {name: type} and the facts that named it
OBJECT_REMOVE = Verb(api("object/remove"), ObjectName, StateReply)
DOMAIN_SHOW = Verb(api("domain/show"), Empty, DomainReply)
EVENTS = Verb(api("events"), EventQuery, EventsReply)
STATUS = Verb(api("status"), Empty, StatusReply)


def newest_events(bus: Bus, limit: int, kind: str | None = None) -> list[Event]:
    """The newest ``limit`` events of the log (of ``kind`` only, if given), oldest first,
    however large: asked for page by page while a reply says there is more."""
    events: list[Event] = []
    before = 0
    while len(events) < limit:
        query = EventQuery(limit=limit - len(events), kind=kind, before=before)
        reply = EVENTS.call(bus, query)
        events[:0] = reply.events
        if not reply.more or not reply.events:
            break
        before = reply.events[0].id
    return events


def newest_goals(
    bus: Bus,
    limit: int | None = None,
    states: list[GoalState] | None = None,
    *,
    before: int = 0,
) -> list[Goal]:
    """The newest ``limit`` goals (all without) in ``states`` (all without) and before
    the goal ``before`` (unless 0), oldest first, however many: asked for page by page
    while a reply says there is more."""
    goals: list[Goal] = []
    while limit is None or len(goals) < limit:
        left = None if limit is None else limit - len(goals)
        reply = GOAL_LIST.call(bus, GoalQuery(states, before=before, limit=left))
        goals[:0] = reply.goals
        if not reply.more or not reply.goals:
            break
        before = reply.goals[0].id
    return goals
