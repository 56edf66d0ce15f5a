"""The high level at work (thesis 5.1.2): the goal planner, the plan executor, the
integrity goals and the sensing rules on one knowledge base, wired together.

It is built once the planner is warm (it needs the domain) and runs while the high level
is active. It follows the events of every process: a change of the world from outside
the plan (a fact or object set, a component reset or repaired) reaches the goal planner,
which looks again at unreachable goals; any change of facts reaches the maintenance
goals; every event but the integrity goals' own makes the integrity rules look again.
"""

from __future__ import annotations

import functools
from collections.abc import Callable, Collection, Mapping
from typing import Any

from executive.bus.clock import Clock
from executive.bus.reports import PlannerStatus
from executive.bus.service import Context
from executive.planning.blocked_tasks import BlockedTasks, blocked_now
from executive.planning.goal_planner import GoalPlanner
from executive.planning.integrity import IntegrityGoals
from executive.planning.integrity_loop import IntegrityLoop
from executive.planning.plan_executor import ExecutionLimits, PlanExecutor, TaskRunner
from executive.planning.planner import Planner
from executive.planning.sensing import Sensing, Subscribe
from executive.planning.timed_facts import TimedFacts
from executive.planning.warm_up import Warm
from knowledge.records import Fact

# events of the world changing outside the plan, and of the plan's own steps changing facts
OUTSIDE_CHANGES = (
    "STATE_SET", "STATE_UNSET", "STATE_TIMED", "OBJECT_ADDED", "COMPONENT_RESET", "REPAIR",
)  # fmt: skip
PLAN_CHANGES = ("START", "END", "FAIL", "CANCEL")


class Deliberation:
    """Goal planner, plan executor, integrity goals and sensing, once the domain is known.

    Args:
        context: the robot, bus and knowledge base.
        warm: the domain and the integrity rules (the warm-up's).
        planner: the warm planner.
        runner: carries out plan steps (the task executor's adapter).
        limits: when a running step times out.
        clock: robot time.
        subscribe: how sensing rules subscribe to their topics.
        diagnoses: the latest diagnosis result, if one came already.
        actions: the actions whose steps ``runner`` carries out (default: the robot's
            tasks; the others complete at once with their effects).
        unavailable: the objects that cannot act now (a fleet's lost robots).
    """

    def __init__(
        self,
        context: Context,
        warm: Warm,
        planner: Planner,
        runner: TaskRunner,
        *,
        limits: ExecutionLimits | None,
        clock: Clock,
        subscribe: Subscribe,
        diagnoses: Mapping[str, Any] | None = None,
        actions: Collection[str] | None = None,
        unavailable: Callable[[], Collection[str]] | None = None,
    ) -> None:
        kb, robot = context.kb, context.robot
        self.domain = warm.domain
        self.planner = planner
        self.executor = PlanExecutor(
            kb,
            runner,
            robot.tasks if actions is None else actions,
            self._replan,
            limits,
            clock=clock,
        )
        self.goals = GoalPlanner(
            kb,
            self.domain,
            planner,
            self.executor,
            blocked=functools.partial(blocked_now, kb, robot),
            unavailable=unavailable,
        )
        self.integrity = IntegrityGoals(kb, self.domain, warm.rules, clock=clock)
        if diagnoses:
            self.integrity.diagnosed(diagnoses)
        self.integrity_loop = IntegrityLoop(
            self.integrity, self.goals, BlockedTasks(kb, robot), clock
        )
        self.sensing = Sensing(
            kb, self.domain, robot.sensing, subscribe=subscribe, changed=self._sensed, clock=clock
        )
        self.timed = TimedFacts(kb, self._sensed)

    def start(self) -> None:
        self.integrity_loop.start()
        self.executor.start()
        self.goals.start()
        self.sensing.start()
        self.timed.start()

    def stop(self) -> None:
        self.timed.stop()
        self.integrity_loop.stop()
        self.sensing.stop()
        self.goals.stop()
        self.executor.stop()

    def followed(self, kind: str, subject: str) -> None:
        """An event was logged, by this process or another."""
        if kind in OUTSIDE_CHANGES:
            self.goals.world_changed(f"{kind} {subject}")
        elif kind in PLAN_CHANGES:
            self.goals.facts_changed(f"{kind} {subject}")
        self.integrity_loop.changed(kind)

    def diagnosed(self, payload: Mapping[str, Any]) -> None:
        self.integrity_loop.diagnosed(payload)

    def status(self) -> PlannerStatus:
        """What the goal planner does now (never waits for it)."""
        return self.goals.status()

    def replan(self, reason: str) -> None:
        """Plan again now, although no step failed, and look again at the goals found
        unreachable (the world changed so that the plan may no longer be carried out, or
        a goal may be reached again: a fleet's robot was lost, or is back)."""
        self.goals.world_changed(reason)
        self.goals.wake(reason, replan=True)

    def _replan(self, reason: str) -> None:
        self.goals.replan(reason)

    def _sensed(self, facts: list[Fact], reason: str) -> None:
        """A sensing rule (or a timed fact) changed facts: as a user's ``dura state set``
        does."""
        self.executor.facts_changed([(f.name, f.args) for f in facts])
        self.goals.wake(reason)
