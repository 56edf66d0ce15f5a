"""The high level's API: goals, plans, the world's facts and objects, events, status."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Annotated, Any

from executive.bus.keys import api
from executive.bus.schema import Between, Payload, Text
from executive.bus.verb import Empty, Verb
from knowledge.records import GoalState

Count = Annotated[int, Between(0, 2**63 - 1)]
Priority = Annotated[int, Between(-(10**9), 10**9)]  # what the CLI accepts too


@dataclass(frozen=True)
class GoalAdd(Payload):
    """A goal expression with its priority, deadline (seconds from now) and source."""

    expression: Text
    priority: Priority = 0
    deadline: float | None = None
    source: str = "user"


@dataclass(frozen=True)
class GoalId(Payload):
    id: int


@dataclass(frozen=True)
class GoalQuery(Payload):
    """Goals in these states (all goals without)."""

    states: list[GoalState] | None = None


@dataclass(frozen=True)
class GoalReply(Payload):
    goal: dict[str, Any]


@dataclass(frozen=True)
class GoalsReply(Payload):
    goals: list[dict[str, Any]]


@dataclass(frozen=True)
class GoalHistory(Payload):
    """A goal and the events that name it."""

    goal: dict[str, Any]
    events: list[dict[str, Any]]


@dataclass(frozen=True)
class PlanReply(Payload):
    """The newest plan (stored) and how its execution stands."""

    plan: dict[str, Any] | None
    execution: dict[str, Any]


@dataclass(frozen=True)
class StateQuery(Payload):
    """Facts matching ``robot_at``, ``(robot_at lab)``, ``(robot_at *)`` (all without)."""

    pattern: str = ""


@dataclass(frozen=True)
class StateReply(Payload):
    facts: list[dict[str, Any]]
    objects: dict[str, str]


@dataclass(frozen=True)
class FactChange(Payload):
    """A fact to set or unset: ``(robot_at lab)``, ``(= (battery) 80)``; ``source`` names
    who changes it (a component's name, or ``user``), as the event log records it."""

    fact: Text
    source: Text = "user"


@dataclass(frozen=True)
class FactReply(Payload):
    fact: dict[str, Any]


@dataclass(frozen=True)
class ObjectAdd(Payload):
    name: Text
    type: Text


@dataclass(frozen=True)
class EventQuery(Payload):
    """Events after a sequence number, of one kind (all without), oldest first: the
    newest ``limit`` of them, or with ``oldest`` the oldest ``limit`` (to page forward
    through the log without a gap)."""

    after: Count = 0
    limit: Count = 100
    kind: str | None = None
    oldest: bool = False


@dataclass(frozen=True)
class EventsReply(Payload):
    events: list[dict[str, Any]]


@dataclass(frozen=True)
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
STATE_GET = Verb(api("state/get"), StateQuery, StateReply)
STATE_SET = Verb(api("state/set"), FactChange, FactReply)
STATE_UNSET = Verb(api("state/unset"), FactChange, FactReply)
OBJECT_ADD = Verb(api("object/add"), ObjectAdd, ObjectAdd)
EVENTS = Verb(api("events"), EventQuery, EventsReply)
STATUS = Verb(api("status"), Empty, StatusReply)
