"""Plan steps carried out over the bus: the port between a high level and a task executor
in different processes (``dura run --only planning`` beside ``--without planning``).

The high level asks for a step's task (:data:`STEP_RUN`), pauses, resumes or cancels it
(:data:`STEP_CONTROL`) and tells which steps are to come (:data:`STEP_UPCOMING`); the
task executor's side reports how each step goes on :data:`STEP_PROGRESS`, by the run id
the high level chose. The keys lie outside ``executive/api``: only the trusted users (the
executive and its separated services) may call them, not operators.
"""

from __future__ import annotations

import enum
from dataclasses import field

from executive.bus.api.free_form import Result
from executive.bus.schema import Payload, Text
from executive.bus.verb import Empty, Verb
from knowledge.record_class import record

STEP_PROGRESS = "executive/steps/progress"  # StepProgress payloads, by run id


@record
class StepSpec(Payload):
    """What the task executor needs of a plan step: its action and objects, the
    parameters they bind, its index and the planned duration."""

    action: Text
    args: list[str] = field(default_factory=list)
    parameters: list[str] = field(default_factory=list)
    index: int = 0
    duration: float | None = None


@record
class StepRun(Payload):
    """Run a plan's step; ``run`` names it in the progress reports and controls.
    ``fleet``: the fleet whose plan it is (``plan_id`` is the fleet's, not one of this
    robot's plans); none for the robot's own high level."""

    run: Text
    plan_id: int
    step: StepSpec
    fleet: Text | None = None


class StepAction(enum.Enum):
    PAUSE = "pause"
    RESUME = "resume"
    CANCEL = "cancel"


@record
class StepControl(Payload):
    """Pause, resume or cancel the step of a run."""

    run: Text
    action: StepAction


@record
class StepsUpcoming(Payload):
    """The steps of the current plan not dispatched yet (none: no plan)."""

    plan_id: int | None = None
    steps: list[StepSpec] = field(default_factory=list)


@record
class StepProgress(Payload):
    """How a step goes: ``started``, ``succeeded`` (``value``: the behavior's result) or
    ``failed`` (``value``: the reason); the names of
    :class:`executive.planning.task_runner.Progress`."""

    run: Text
    progress: Text
    value: Result = None


STEP_RUN = Verb("executive/steps/run", StepRun, Empty, timeout=10.0)
STEP_CONTROL = Verb("executive/steps/control", StepControl, Empty, timeout=10.0)
STEP_UPCOMING = Verb("executive/steps/upcoming", StepsUpcoming, Empty, timeout=10.0)
