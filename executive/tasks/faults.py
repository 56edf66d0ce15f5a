"""Fault bookkeeping: count faults in the knowledge base and decide what each one means.

A fault of a component is its process exiting, a repair command from the rule engine
(restart, mark faulty) or a user's request to restart it (thesis 7.1.3). Every fault
counts in the knowledge base, so a restarted executive remembers it.

- A functionality below ``max_faults`` is restarted. At ``max_faults`` (or when marked
  faulty) it is permanently faulty, and so is every functionality that can only run on
  top of it: the tasks using them need new configurations.
- A running task hit by a fault of one of its functionalities pauses its behavior if
  the behavior is reconfigurable, else stops it and starts it again once the
  configuration is repaired. Neither counts against the behavior's ``max_restarts``.
- A failing behavior is restarted (warm, from its achievements) up to ``max_restarts``
  times within its task; then the task fails.

This module decides; :mod:`executive.tasks.fault_handling` carries the decisions out.
"""

from __future__ import annotations

import dataclasses
import enum
from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass, field

from knowledge.availability import Availability
from knowledge.description import ComponentSpec, FunctionalitySpec, Kind, RobotDescription
from knowledge.errors import KnowledgeError
from knowledge.knowledge_base import KnowledgeBase


class TaskAction(enum.Enum):
    PAUSE = "pause"  # reconfigurable: pause now, resume on the repaired configuration
    RESTART = "restart"  # stop now, start again (warm) on the repaired configuration
    FAIL = "fail"  # the task fails


@dataclass(frozen=True)
class TaskUsage:
    """What fault handling needs to know of a running task."""

    id: str
    behavior: str
    functionalities: frozenset[str] = frozenset()


@dataclass(frozen=True)
class FaultDecision:
    """What one fault means.

    Args:
        component: the faulty component.
        kind: whether it is a functionality or a behavior.
        count: its faults so far.
        permanent: it is permanently faulty now.
        unusable: functionalities that this fault made unusable, each with the reason:
            the component itself and those that can only run on top of it.
        tasks: the running tasks it hits and what to do with each one's behavior.
    """

    component: str
    kind: Kind
    count: int
    permanent: bool
    unusable: Mapping[str, str] = field(default_factory=dict)
    tasks: Mapping[str, TaskAction] = field(default_factory=dict)
    unavailable: bool = False  # its host is lost: it cannot run anywhere until it is back

    @property
    def restart(self) -> bool:
        """Restart the component: a functionality that is not permanently faulty, and
        whose host is there."""
        return self.kind is Kind.FUNCTIONALITY and not self.permanent and not self.unavailable

    @property
    def reschedule(self) -> bool:
        """Configurations must change: functionalities became unusable."""
        return bool(self.unusable)


class Faults:
    """The faults of a robot's components, kept in its knowledge base.

    Registers every component in the knowledge base (one that is there already keeps
    its rating and fault history). Counts behavior restarts per task in memory.

    Args:
        unavailable: the components that cannot run now because their host is lost
            (none by default); unusable like the permanently faulty ones while it lasts.
    """

    def __init__(
        self,
        robot: RobotDescription,
        kb: KnowledgeBase,
        unavailable: Callable[[], frozenset[str]] = frozenset,
    ) -> None:
        self.robot = robot
        self.kb = kb
        self.unavailable = unavailable
        self._restarts: dict[str, int] = {}
        with kb.transaction():
            for f in robot.functionalities.values():
                kb.register_component(f.name, f.rating)
            for b in robot.behaviors.values():
                kb.register_component(b.name, 1.0)

    def faulty(self) -> frozenset[str]:
        """The permanently faulty components."""
        return frozenset(c.name for c in self.kb.components() if c.permanent_fault)

    def unusable(self) -> frozenset[str]:
        """The components no configuration may use now: permanently faulty, or placed on
        a host that is lost."""
        return self.faulty() | self.unavailable()

    def ratings(self) -> dict[str, float]:
        """Each component's rating as the knowledge base holds it."""
        return {c.name: c.rating for c in self.kb.components()}

    def functionalities(self) -> list[FunctionalitySpec]:
        """The robot's functionalities with the ratings the knowledge base holds."""
        ratings = self.ratings()
        return [
            dataclasses.replace(f, rating=ratings.get(f.name, f.rating))
            for f in self.robot.functionalities.values()
        ]

    def availability(self, *, besides: str = "") -> Availability:
        """What can run (``besides``: as if that component's host were there)."""
        unusable = self.faulty() | (self.unavailable() - {besides})
        return Availability.of(self.robot.functionalities.values(), unusable)

    def fault(
        self,
        name: str,
        reason: str,
        running: Iterable[TaskUsage] = (),
        *,
        permanent: bool = False,
    ) -> FaultDecision:
        """Count a fault of a component and decide what it means. A component whose host
        is lost is unavailable, not faulty: no fault is counted and it is not restarted;
        the tasks it hits move to what is left.

        Args:
            name: the component.
            reason: why it is faulty (kept in the knowledge base).
            running: the running tasks.
            permanent: mark it permanently faulty at once (a repair command).

        Raises:
            KnowledgeError: the robot has no component of that name.
        """
        component = self._component(name)
        before = self.availability(besides=name)
        unavailable = name in self.unavailable()
        with self.kb.transaction():
            limit = component.max_faults if isinstance(component, FunctionalitySpec) else None
            if unavailable and not permanent:  # its host is lost, not the component
                record = self.kb.component(name)
            else:
                record = self.kb.record_fault(name, reason, max_faults=limit)
            if permanent and not record.permanent_fault:
                record = self.kb.mark_permanent_fault(name, reason)
        decision = FaultDecision(name, component.kind, record.fault_count, record.permanent_fault,
                                 unavailable=unavailable)  # fmt: skip
        if isinstance(component, FunctionalitySpec):
            return self._functionality_fault(decision, before, running)
        return self._behavior_fault(decision, running)

    def reset(self, name: str) -> list[str]:
        """Clear a component's faults after maintenance; returns the functionalities usable again."""
        self._component(name)
        before = self.availability()
        self.kb.reset_component(name)
        return sorted(self.availability().usable - before.usable)

    def finished(self, task_id: str) -> None:
        """Forget a task's behavior restarts (it ended)."""
        self._restarts.pop(task_id, None)

    def _component(self, name: str) -> ComponentSpec:
        if name not in self.robot.components:
            raise KnowledgeError(f"robot '{self.robot.name}' has no component '{name}'")
        return self.robot.components[name]

    def _functionality_fault(
        self, decision: FaultDecision, before: Availability, running: Iterable[TaskUsage]
    ) -> FaultDecision:
        """Tasks on the functionality, or on anything it took down, repair their configurations."""
        after = self.availability()
        unusable = {f: why for f, why in after.unusable.items() if f in before.usable}
        hit = {decision.component} | unusable.keys()
        tasks = {
            t.id: TaskAction.PAUSE
            if self.robot.behaviors[t.behavior].reconfigurable
            else TaskAction.RESTART
            for t in running
            if t.functionalities & hit
        }
        return dataclasses.replace(decision, unusable=unusable, tasks=tasks)

    def _behavior_fault(
        self, decision: FaultDecision, running: Iterable[TaskUsage]
    ) -> FaultDecision:
        """The task running the behavior restarts it, up to ``max_restarts`` times."""
        behavior = self.robot.behaviors[decision.component]
        tasks: dict[str, TaskAction] = {}
        for t in running:
            if t.behavior != behavior.name:
                continue
            restarts = self._restarts.get(t.id, 0)
            if decision.permanent or decision.unavailable or restarts >= behavior.max_restarts:
                tasks[t.id] = TaskAction.FAIL
            else:
                self._restarts[t.id] = restarts + 1
                tasks[t.id] = TaskAction.RESTART
        return dataclasses.replace(decision, tasks=tasks)
