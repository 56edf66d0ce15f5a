"""System configurations: which functionalities serve which tasks, and how to change them.

A functionality runs while at least one task's configuration holds it (reference
counting), so a shared one (cam for move_to and take_picture, thesis 7.5) starts with
the first task that needs it and stops with the last. Going from one configuration to
another stops what no task holds any more, dependents first, and starts what is
missing, dependencies first: lidar starts before lidar_filter and stops after it.

Besides the tasks' configurations, a configuration may keep functionalities running
that no task holds now (``reserved``): those the plan's upcoming steps need, and those
that linger after their last task (:func:`executive.tasks.decisions.keep_running`).
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field

import networkx as nx

from knowledge.description import FunctionalitySpec


@dataclass(frozen=True)
class Transition:
    """The steps from one system configuration to another.

    Args:
        stop: functionalities to stop, in this order (those that require others first).
        start: functionalities to start, in this order (those that others require first).
        keep: functionalities that keep running.
        resume: idle spares a task or reservation needs now, in this order (those that
            require others first: a consumer is listening when its provider resumes).
        pause: functionalities that keep running but only spares hold now.
    """

    stop: tuple[str, ...] = ()
    start: tuple[str, ...] = ()
    keep: frozenset[str] = frozenset()
    resume: tuple[str, ...] = ()
    pause: tuple[str, ...] = ()

    @property
    def empty(self) -> bool:
        """Nothing starts or stops (spares may resume or pause)."""
        return not self.stop and not self.start


@dataclass(frozen=True)
class SystemConfiguration:
    """The configurations of the tasks that hold functionalities.

    ``tasks`` maps a task id to its providers: capability → functionality, closed
    under ``requires`` (as the scheduler assigns them). ``reserved`` maps a reason to
    keep functionalities running (an upcoming step, a linger) to providers likewise, and
    ``standby`` a warm spare (``standby: true``) to the providers it runs on; what only
    a spare holds runs paused.
    """

    tasks: Mapping[str, Mapping[str, str]] = field(default_factory=dict)
    reserved: Mapping[str, Mapping[str, str]] = field(default_factory=dict)
    standby: Mapping[str, Mapping[str, str]] = field(default_factory=dict)

    @property
    def users(self) -> dict[str, frozenset[str]]:
        """Each running functionality and the tasks (or reservations) holding it (its
        reference count)."""
        out: dict[str, set[str]] = {}
        for task, providers in self.holders():
            for f in providers.values():
                out.setdefault(f, set()).add(task)
        return {f: frozenset(ts) for f, ts in sorted(out.items())}

    @property
    def functionalities(self) -> frozenset[str]:
        """The functionalities that run."""
        return frozenset(f for _, providers in self.holders() for f in providers.values())

    @property
    def held(self) -> frozenset[str]:
        """The functionalities a task holds (not only a reservation)."""
        return frozenset(f for providers in self.tasks.values() for f in providers.values())

    @property
    def idle(self) -> frozenset[str]:
        """The functionalities only spares hold: they run paused."""
        active = frozenset(
            f for _, providers in (*self.tasks.items(), *self.reserved.items())
            for f in providers.values()
        )  # fmt: skip
        return self.functionalities - active

    def holders(self) -> list[tuple[str, Mapping[str, str]]]:
        """Every task, reservation and spare with its providers."""
        return [*self.tasks.items(), *self.reserved.items(), *self.standby.items()]

    def with_task(self, task: str, providers: Mapping[str, str]) -> SystemConfiguration:
        """This configuration with a task's providers added (or replaced)."""
        return SystemConfiguration(
            {**self.tasks, task: dict(providers)}, self.reserved, self.standby
        )

    def without_task(self, task: str) -> SystemConfiguration:
        """This configuration without a task: what only it held can stop."""
        return SystemConfiguration(
            {t: p for t, p in self.tasks.items() if t != task}, self.reserved, self.standby
        )

    def transition(
        self, target: SystemConfiguration, functionalities: Iterable[FunctionalitySpec]
    ) -> Transition:
        """The steps from this configuration to ``target``.

        The order follows the configurations themselves: a functionality depends on
        the provider a task's configuration chose for each capability it requires.
        """
        specs = list(functionalities)
        running, wanted = self.functionalities, target.functionalities
        stop, start, keep = running - wanted, wanted - running, running & wanted
        return Transition(
            stop=tuple(reversed(_order(self, stop, specs))),
            start=_order(target, start, specs),
            keep=keep,
            resume=tuple(reversed(_order(target, (self.idle & keep) - target.idle, specs))),
            pause=_order(target, (target.idle & keep) - self.idle, specs),
        )


def _order(
    configuration: SystemConfiguration,
    names: frozenset[str],
    functionalities: Iterable[FunctionalitySpec],
) -> tuple[str, ...]:
    """Names in dependency order (providers first, ties by name)."""
    requires = {f.name: f.requires for f in functionalities}
    graph: nx.DiGraph = nx.DiGraph()
    graph.add_nodes_from(names)
    for _, providers in configuration.holders():
        for f in providers.values():
            for capability in requires.get(f, ()):
                provider = providers.get(capability)
                if f in names and provider in names and provider != f:
                    graph.add_edge(provider, f)
    return tuple(nx.lexicographical_topological_sort(graph))
