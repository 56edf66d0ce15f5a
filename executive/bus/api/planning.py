"""The high level's API: goals, plans, the world's facts and objects, the domain, events,
status."""

from __future__ import annotations

from dataclasses import field
from typing import Annotated, Any

from executive.bus.keys import api
from executive.bus.schema import Between, Payload, Text, payload
from executive.bus.verb import Empty, Verb
from knowledge.transitions import GoalState

Count = Annotated[int, Between(0, 2**63 - 1)]
Priority = Annotated[int, Between(-(10**9), 10**9)]  # what the CLI accepts too


@payload
class GoalAdd(Payload):
    """A goal expression with its priority, deadline (seconds from now) and source;
    ``keep``: a maintenance goal, re-posted whenever it stops holding."""

    expression: Text
    priority: Priority = 0
    deadline: float | None = None
    source: str = "user"
    keep: bool = False


@payload
class GoalId(Payload):
    """A goal, by id."""

    id: int


@payload
class GoalQuery(Payload):
    """Goals in these states (all goals without)."""

    states: list[GoalState] | None = None


@payload
class GoalReply(Payload):
    """A goal as stored."""

    goal: dict[str, Any]


@payload
class GoalsReply(Payload):
    """Goals as stored, by id."""

    goals: list[dict[str, Any]]


@payload
class GoalHistory(Payload):
    """A goal and the events that name it."""

    goal: dict[str, Any]
    events: list[dict[str, Any]]


@payload
class PlanReply(Payload):
    """The newest plan (stored) and how its execution stands."""

    plan: dict[str, Any] | None
    execution: dict[str, Any]


@payload
class DryRun(Payload):
    """Plan for the open goals, and the goal expressions ``goals`` as if they were added
    now, on the live state without executing (seconds to search; the robot's planner
    timeout without)."""

    timeout: Annotated[float, Between(0.1, 3600.0)] | None = None
    goals: list[Text] = field(default_factory=list)


@payload
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
    steps: list[dict[str, Any]]
    makespan: float | None = None
    asked: list[str] = field(default_factory=list)


@payload
class StateQuery(Payload):
    """Facts matching ``robot_at``, ``(robot_at lab)``, ``(robot_at *)`` (all without)."""

    pattern: str = ""


@payload
class StateReply(Payload):
    """Facts (name, args, value, text) and objects (name -> type)."""

    facts: list[dict[str, Any]]
    objects: dict[str, str]


@payload
class FactChange(Payload):
    """A fact to set or unset: ``(robot_at lab)``, ``(= (battery) 80)``; ``source`` names
    who changes it (a component's name, or ``user``), as the event log records it."""

    fact: Text
    source: Text = "user"


@payload
class FactReply(Payload):
    """The fact as it was set or unset."""

    fact: dict[str, Any]


@payload
class ObjectAdd(Payload):
    """An object of a domain type."""

    name: Text
    type: Text


@payload
class ObjectName(Payload):
    """An object of the world, by name."""

    name: Text


@payload
class DomainReply(Payload):
    """The robot's domain: ``types`` ``{name, parent}``; ``predicates`` and ``functions``
    ``{name, parameters}`` (their types); ``actions`` ``{name, parameters [[?name, type]],
    durative, duration (as written), task, behavior, goal (the behavior's goal fields),
    blocked (why it cannot run now, or null)}``; ``constants`` by name, their types."""

    name: str
    path: str
    types: list[dict[str, Any]]
    predicates: list[dict[str, Any]]
    functions: list[dict[str, Any]]
    actions: list[dict[str, Any]]
    constants: dict[str, str]


@payload
class EventQuery(Payload):
    """Events after a sequence number, of one kind (all without), oldest first: the
    newest ``limit`` of them, or with ``oldest`` the oldest ``limit`` (to page forward
    through the log without a gap)."""

    after: Count = 0
    limit: Count = 100
    kind: str | None = None
    oldest: bool = False


@payload
class EventsReply(Payload):
    """Events of the log, oldest first."""

    events: list[dict[str, Any]]


@payload
class StatusReply(Payload):
    """Everything at a glance. ``tasks`` and ``components`` come from the task executor
    and the launcher: a list, or ``{"error": reason}`` when that service did not answer.
    ``planning`` says whether the goal planner is computing a plan, since when and why."""

    robot: str
    goals: list[dict[str, Any]]
    plan: dict[str, Any] | None
    execution: dict[str, Any]
    diagnoses: dict[str, Any]
    faults: list[dict[str, Any]]
    tasks: Any = None
    components: Any = None
    planning: dict[str, Any] | None = None


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
