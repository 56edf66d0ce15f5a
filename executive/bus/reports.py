"""What the services report about what they do, as typed records on the wire: how the
plan executor's execution stands (:class:`ExecutionStatus`), what the goal planner does
(:class:`PlannerStatus`), the task executor's tasks (:class:`ExecutorTask`, in time
:class:`ScheduledTask`), the launcher's components (:class:`ComponentEntry`) and the
diagnosis engine's newest result (:class:`DiagnosisInfo`, the payload of
``diagnoses``).

The replies of :mod:`executive.bus.api` carry them (``status`` all of them), beside the
knowledge base's records (:mod:`knowledge.records`); the services build them and the
CLI, the dashboard and the test harness read them by attribute.
"""

from __future__ import annotations

import enum
from collections.abc import Mapping
from typing import TYPE_CHECKING, Any

from executive.bus.api.free_form import GoalFields, Result
from executive.bus.schema import Payload
from executive.bus.states import Lifecycle
from knowledge.record_class import record
from knowledge.records import KeyAccess

if TYPE_CHECKING:
    from knowledge.records import Plan

# --- the high level: the plan executor and the goal planner ---------------------------


@record
class StepStatus:
    """A step of the plan under way: its index, its label (``move_to(dock, lab)``) and
    its state."""

    index: int
    step: str
    state: str


@record
class GoalProgress:
    """A goal of the plan under way, and whether it is achieved."""

    id: int
    achieved: bool


@record
class ExecutionStatus:
    """How the execution stands, as of the plan executor's last job (for ``dura
    status``)."""

    plan: int | None = None
    paused: bool = False
    failed: bool = False
    steps: tuple[StepStatus, ...] = ()
    goals: tuple[GoalProgress, ...] = ()

    def states_of(self, plan: Plan) -> dict[int, str]:
        """Each step's state of ``plan``: live while this execution runs it (paused steps
        too), else as stored."""
        states = {s.index: s.state for s in plan.steps}
        if self.plan == plan.id:
            states.update({s.index: s.state for s in self.steps})
        return states


class RoundPhase(enum.Enum):
    """Where a planning round is."""

    PAUSING = "pausing"  # the executor pauses; critical tasks finish first
    SEARCHING = "searching"  # the planner searches for a plan


@record
class PlannerStatus:
    """What the goal planner is doing, as of its last job (for ``dura status``)."""

    planning: bool = False  # a round is under way
    phase: RoundPhase | None = None
    reason: str = ""  # why it began
    goals: tuple[int, ...] = ()  # the goals open when it began
    since: float | None = None  # when it began (seconds since the epoch)
    planned: tuple[int, ...] = ()  # the goals of the plan handed to the executor
    starting: bool = False  # the planner is still loading the domain (at the start)


# --- the task executor ----------------------------------------------------------------


@record
class ExecutorTask:
    """A task as the task executor holds it: its name (the action and its objects, or
    the behavior), the behavior and its goal, its state (``waiting``, ``starting``,
    ``running``, ``paused``, ``repairing``, ``succeeded``, ``failed``, ``cancelled``),
    the functionality serving each capability it needs and those functionalities, its
    planned duration, why it is where it is, why it ended (``succeeded``,
    ``behavior_failed``, ``user``, ...) and the behavior's result."""

    id: str
    name: str
    behavior: str
    goal: GoalFields
    state: str
    providers: Mapping[str, str]
    functionalities: tuple[str, ...]
    duration: float
    reason: str = ""
    ended_by: str | None = None
    result: Result | None = None


@record
class ScheduledTask(ExecutorTask):
    """A waiting or running task placed in time: seconds from now."""

    start: float = 0.0
    end: float = 0.0


# --- the launcher ---------------------------------------------------------------------


@record
class ComponentEntry(KeyAccess, Payload):
    """A component as lists show it: its kind (``functionality``, ``behavior``), the
    host it runs on, its state as ``component/<name>/state`` reports it (a pid only
    while it runs) and, in ``component/list``, where its log is."""

    kind: str
    host: str
    component: str
    state: Lifecycle
    pid: int | None
    exit_code: int | None
    signal: int | None
    reason: str
    stamp: float
    log: str | None = None
    output: tuple[str, ...] = ()  # what it wrote last when it failed: its exception


# --- the diagnosis engine --------------------------------------------------------------

DIAGNOSIS_STATUSES = ("OK", "DIAGNOSED", "INCONSISTENT", "TIMEOUT")


@record
class DiagnosisInfo:
    """The payload of ``diagnoses``: the newest diagnosis result.

    ``status`` is OK (the all-clear), DIAGNOSED, INCONSISTENT or TIMEOUT.
    ``diagnoses`` lists subset-minimal sets of faulty nodes (or behaviors), each
    sorted, smallest first. ``conflicts`` and ``failed`` are observers as
    ``{type, resource, callerids}``: the observations that contradict each other
    (INCONSISTENT) and those that failed.
    """

    status: str
    diagnoses: tuple[tuple[str, ...], ...] = ()
    conflicts: tuple[dict[str, Any], ...] = ()
    failed: tuple[dict[str, Any], ...] = ()
    elapsed: float = 0.0
    stamp: float = 0.0

    @property
    def possibly_faulty(self) -> frozenset[str]:
        """Every name that some diagnosis names."""
        return frozenset(name for diagnosis in self.diagnoses for name in diagnosis)

    def to_payload(self) -> dict[str, Any]:
        return {
            "status": self.status,
            "diagnoses": [list(d) for d in self.diagnoses],
            "conflicts": list(self.conflicts),
            "failed": list(self.failed),
            "elapsed": self.elapsed,
            "stamp": self.stamp,
        }

    @classmethod
    def from_payload(cls, payload: dict[str, Any]) -> DiagnosisInfo:
        """Read a payload; raises ``KeyError``/``ValueError``/``TypeError`` if malformed
        (a status that is none of the four, a diagnosis that is not a list of names)."""
        status = payload["status"]
        if status not in DIAGNOSIS_STATUSES:
            raise ValueError(f"'status' must be one of {', '.join(DIAGNOSIS_STATUSES)}")
        diagnoses = payload["diagnoses"]
        if not isinstance(diagnoses, list) or not all(
            isinstance(d, list) and all(isinstance(n, str) for n in d) for d in diagnoses
        ):
            raise TypeError("'diagnoses' must be a list of lists of names")
        conflicts, failed = payload.get("conflicts", []), payload.get("failed", [])
        for key, value in (("conflicts", conflicts), ("failed", failed)):
            if not isinstance(value, list) or not all(isinstance(v, dict) for v in value):
                raise TypeError(f"'{key}' must be a list of observers")
        return cls(
            status=status,
            diagnoses=tuple(tuple(d) for d in diagnoses),
            conflicts=tuple(conflicts),
            failed=tuple(failed),
            elapsed=float(payload.get("elapsed", 0.0)),
            stamp=float(payload.get("stamp", 0.0)),
        )
