"""Configuration changes carried out on the launcher: the system configuration that runs,
and the components the task executor started and keeps running.

A change stops what no task holds any more (dependents first) and starts what is
missing (dependencies first), as :meth:`SystemConfiguration.transition` orders it. A
component the executor starts and that becomes ready joins the diagnosis model; one
it stops leaves it. A start that fails is reported back: it is a fault of that
component, which the fault handling counts.

A component started by hand (``dura component start``) is kept running like the
others, and no configuration change stops it: only a stop by hand (when no task holds
it) or a permanent fault does.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Mapping

from executive.bus.payloads import ComponentState, Lifecycle
from executive.runtime.launcher import Launcher
from executive.tasks.configuration import SystemConfiguration, Transition
from executive.tasks.diagnosis_model import DiagnosisModelSync
from knowledge.knowledge_base import KnowledgeBase


class Configurator:
    """Brings the running components in line with the tasks' configurations.

    Args:
        kb: where each change is logged (CONFIGURATION).
        launcher: starts and stops the component processes.
        model: the diagnosis model to keep in line.
        before_start: called before each component start (which may take seconds), so
            that the executor's status shows what is being started.
    """

    def __init__(
        self,
        kb: KnowledgeBase,
        launcher: Launcher,
        model: DiagnosisModelSync,
        *,
        before_start: Callable[[], None] = lambda: None,
    ) -> None:
        self.kb = kb
        self.launcher = launcher
        self.model = model
        self._before_start = before_start
        self._configuration = SystemConfiguration()
        self._expected: set[str] = set()  # components we started and keep running
        self._by_hand: set[str] = set()  # started by hand: only a stop by hand ends them

    @property
    def configuration(self) -> SystemConfiguration:
        """The system configuration that runs (or is being brought up)."""
        return self._configuration

    def apply(
        self, target: SystemConfiguration, transition: Transition, why: str
    ) -> Mapping[str, str]:
        """Change to ``target`` by ``transition``; the functionalities that did not start,
        each with the launcher's reason."""
        self._configuration = target
        if transition.empty:
            return {}
        self.kb.log_event(
            "CONFIGURATION",
            ", ".join(sorted(target.functionalities)) or "nothing",
            {"stop": list(transition.stop), "start": list(transition.start), "why": why},
        )
        for name in transition.stop:
            self.release(name, "no task needs it")
        failed = [n for n in transition.start if self.start(n).state is not Lifecycle.READY]
        return {name: self.launcher.state(name).reason for name in failed}

    def start(self, name: str) -> ComponentState:
        """Start a component (a functionality or a behavior) and wait until it is ready."""
        self._expected.add(name)
        self._before_start()
        state = self.launcher.start(name)
        if state.state is Lifecycle.READY:
            self.model.add(name)
        else:
            self._expected.discard(name)
        return state

    def stop(self, name: str, reason: str) -> None:
        self._expected.discard(name)
        self.model.remove(name)
        self.launcher.stop(name, reason)

    def release(self, name: str, reason: str) -> None:
        """No task needs it any more: stop it, unless it was started by hand."""
        if name not in self._by_hand:
            self.stop(name, reason)

    def start_by_hand(self, name: str) -> ComponentState:
        """Start a component for a user, kept running until the user stops it."""
        self._by_hand.add(name)
        state = self.start(name)
        if state.state is not Lifecycle.READY:
            self._by_hand.discard(name)
        return state

    def stop_by_hand(self, name: str, *, held: bool) -> ComponentState:
        """A user stops a component: it stops unless a task holds it (``held``)."""
        self._by_hand.discard(name)
        if not held:
            self.stop(name, "stopped by hand")
        return self.launcher.state(name)

    def by_hand(self, name: str) -> bool:
        """It was started by hand and not stopped by hand since."""
        return name in self._by_hand

    def forget_by_hand(self, name: str) -> None:
        """It is no longer kept running for a user (it is permanently faulty)."""
        self._by_hand.discard(name)

    def restart(self, name: str, reason: str) -> ComponentState:
        self.stop(name, reason)
        return self.start(name)

    def expects(self, name: str) -> bool:
        """We started it and keep it running: its exit is a fault."""
        return name in self._expected

    def lost(self, name: str) -> None:
        """It exited on its own: no longer ours to keep running."""
        self._expected.discard(name)

    def alive(self, name: str) -> bool:
        return self.launcher.state(name).state.is_alive

    def ready(self, names: Iterable[str]) -> bool:
        """Every one of them is ready."""
        return all(self.launcher.state(n).state is Lifecycle.READY for n in names)
