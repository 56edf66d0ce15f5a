"""Configuration changes carried out on the launcher: the system configuration that runs,
and the components the task executor started and keeps running.

A change makes before it breaks: the warm spares a task needs now resume and what is
missing starts, all at once (a configuration change costs one component start, not the
sum), and only then does what no task holds any more stop. (Sequentially, as
:meth:`SystemConfiguration.transition` orders it, for robots that need it: stops first,
dependents first, then starts, dependencies first.) Spares no task needs run paused. A
component the executor starts and that becomes ready joins the diagnosis model; one it
stops leaves it. A start that fails is reported back: it is a fault of that component,
which the fault handling counts.

A component started by hand (``dura component start``) is kept running like the
others, and no configuration change stops it: only a stop by hand (when no task holds
it) or a permanent fault does.
"""

from __future__ import annotations

import logging
from collections.abc import Callable, Iterable, Mapping, Sequence

from executive.bus.helpers import Helpers
from executive.bus.payloads import ComponentState
from executive.bus.states import Lifecycle
from executive.runtime.launcher import Launcher
from executive.tasks.configuration import SystemConfiguration, Transition
from executive.tasks.diagnosis_model import DiagnosisModelSync
from knowledge.errors import ComponentError
from knowledge.knowledge_base import KnowledgeBase

log = logging.getLogger("dura.task_executor")

RUNNING = (Lifecycle.READY, Lifecycle.PAUSED)  # a started component is in one of these


class Configurator:
    """Brings the running components in line with the tasks' configurations.

    Args:
        kb: where each change is logged (CONFIGURATION).
        launcher: starts and stops the component processes.
        model: the diagnosis model to keep in line.
        before_start: called before each component start (which may take seconds), so
            that the executor's status shows what is being started.
        sequential: change configurations as dura first did: stop what goes first, then
            start what comes one after another, in dependency order (for robots whose
            components need their providers up when they start).
    """

    def __init__(
        self,
        kb: KnowledgeBase,
        launcher: Launcher,
        model: DiagnosisModelSync,
        *,
        before_start: Callable[[], None] = lambda: None,
        sequential: bool = False,
    ) -> None:
        self.kb = kb
        self.launcher = launcher
        self.model = model
        self.sequential = sequential
        self._before_start = before_start
        self._configuration = SystemConfiguration()
        self._expected: set[str] = set()  # components we started and keep running
        self._by_hand: set[str] = set()  # started by hand: only a stop by hand ends them
        self._helpers = Helpers("configure")  # the starts and stops that run at once

    @property
    def configuration(self) -> SystemConfiguration:
        """The system configuration that runs (or is being brought up)."""
        return self._configuration

    def apply(
        self, target: SystemConfiguration, transition: Transition, why: str
    ) -> Mapping[str, str]:
        """Change to ``target`` by ``transition``; the functionalities that did not start,
        each with the launcher's reason.

        Make before break: spares needed now resume and what is missing starts, all at
        once, before what is no longer needed stops (``sequential``: stop first, then
        start one after another in dependency order).
        """
        self._configuration = target
        resume = [n for n in transition.resume if self.launcher.state(n).state is Lifecycle.PAUSED]
        pause = [n for n in transition.pause if self.launcher.state(n).state is Lifecycle.READY]
        if transition.empty and not resume and not pause:
            return {}
        if not transition.empty:
            self.kb.log_event(
                "CONFIGURATION",
                ", ".join(sorted(target.functionalities)) or "nothing",
                {"stop": list(transition.stop), "start": list(transition.start), "why": why,
                 "resume": resume},
            )  # fmt: skip
        if self.sequential:
            for name in transition.stop:
                self.release(name, "no task needs it")
        for name in resume:
            self._switch(name, pause=False)
        failed = self._start_all(transition.start)
        for name in pause:
            self._switch(name, pause=True)
        if not self.sequential:
            self._stop_all(transition.stop)
        return {name: self.launcher.state(name).reason for name in failed}

    def start(self, name: str) -> ComponentState:
        """Start a component (a functionality or a behavior) and wait until it is ready
        (paused, for a spare no task needs)."""
        self._expected.add(name)
        self._before_start()
        return self._started(name, self.launcher.start(name))

    def start_soon(self, name: str, post: Callable[[Callable[[], None]], None]) -> None:
        """Start a component on a helper thread and return at once; what follows its
        start (the diagnosis model, or its failure) is posted. A start or a stop of the
        same component meanwhile waits for this one."""
        self._expected.add(name)
        self._before_start()

        def start() -> None:
            try:
                state = self.launcher.start(name)
            except ComponentError as e:  # the launcher closes
                log.warning("cannot start '%s': %s", name, e)
                state = self.launcher.state(name)
            post(lambda: self._started_soon(name, state))

        self._helpers.run(start)

    def _started_soon(self, name: str, state: ComponentState) -> None:
        """A start begun by :meth:`start_soon` is over (a failed one is tried again when
        a task needs the component, and is a fault then)."""
        if state.state is not Lifecycle.READY:
            log.warning("'%s' did not start ahead of its task: %s", name, state.reason)
        if name in self._expected and self.launcher.state(name).state in RUNNING:
            self._started(name, state)
        elif self.launcher.state(name).state not in RUNNING:
            self._expected.discard(name)

    def _started(self, name: str, state: ComponentState) -> ComponentState:
        if state.state is not Lifecycle.READY:
            self._expected.discard(name)
            return state
        self.model.add(name)
        if name in self._configuration.idle:
            return self._switch(name, pause=True)
        return state

    def _start_all(self, names: Sequence[str]) -> list[str]:
        """Start components, all at once unless sequential; those that did not start."""
        if self.sequential or len(names) < 2:
            return [n for n in names if self.start(n).state not in RUNNING]
        self._expected.update(names)
        self._before_start()
        states = self._helpers.map(self.launcher.start, names)
        return [n for n, s in zip(names, states, strict=True)
                if self._started(n, s).state not in RUNNING]  # fmt: skip

    def _stop_all(self, names: Sequence[str]) -> None:
        """Stop what no task needs (unless started by hand), all at once."""
        stopping = [n for n in names if n not in self._by_hand]
        for name in stopping:
            self._expected.discard(name)
            self._unmodel(name)
        self._helpers.map(lambda n: self.launcher.stop(n, "no task needs it"), stopping)

    def _switch(self, name: str, *, pause: bool) -> ComponentState:
        """Pause a spare no task needs, or resume one a task needs now."""
        try:
            return self.launcher.pause(name) if pause else self.launcher.resume(name)
        except ComponentError as e:  # it ended meanwhile: its exit is handled as such
            log.warning("cannot %s '%s': %s", "pause" if pause else "resume", name, e)
            return self.launcher.state(name)

    def stop(self, name: str, reason: str, *, wait: bool = True) -> None:
        """Stop a component; ``wait=False``: return at once, the stop goes on meanwhile
        (a start of the same component waits for it)."""
        self._expected.discard(name)
        self._unmodel(name)
        if wait:
            self.launcher.stop(name, reason)
        else:
            self.launcher.stop_soon(name, reason)

    def release(self, name: str, reason: str, *, wait: bool = True) -> None:
        """No task needs it any more: stop it, unless it was started by hand."""
        if name not in self._by_hand:
            self.stop(name, reason, wait=wait)

    def _unmodel(self, name: str) -> None:
        """It stops: it leaves the diagnosis model, unless its host is lost (it stays
        there, reported unavailable, until the host is back)."""
        if name not in self.launcher.unavailable():
            self.model.remove(name)

    def host_back(self, names: Iterable[str]) -> None:
        """A lost host is back: those of its components that do not run leave the
        diagnosis model."""
        for name in names:
            if not self.alive(name):
                self.model.remove(name)

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
