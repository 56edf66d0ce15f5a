"""Fault handling carried out: what :mod:`executive.tasks.faults` decides, done.

A fault of a component is its process exiting while the executor keeps it running, a
start that failed, a repair command or a user's restart or mark. Below its
``max_faults`` a functionality is restarted while the behaviors on it pause
(reconfigurable) or stop, and they go on once it is ready again; at ``max_faults`` it
is permanently faulty, stopped, and the tasks are scheduled again on what is left. A
behavior's fault is its task's: restarted up to ``max_restarts``, then the task fails.
A component started by hand is supervised the same way: its exit is a fault, and it is
restarted (a behavior without a task up to its ``max_restarts``) until it is
permanently faulty. A component whose host is lost is unavailable, not faulty: no
fault is counted, no repair restarts it, and its tasks move to the alternatives on other
hosts (or fail, and the planner plans again); when its host agent is back, so is it.
"""

from __future__ import annotations

from collections.abc import Callable

from executive.bus.api.tasks import FaultReply
from executive.bus.payloads import ComponentState
from executive.bus.states import Lifecycle
from executive.runtime.launcher import Launcher
from executive.tasks.configurator import Configurator
from executive.tasks.faults import Faults, TaskAction
from executive.tasks.ledger import TaskLedger
from executive.tasks.supervision import BehaviorSupervisor, End, Post
from executive.tasks.task import TaskEnd
from knowledge.description import Kind, RobotDescription
from knowledge.knowledge_base import KnowledgeBase


class FaultHandler:
    """Counts faults, repairs what they hit, and clears faults after maintenance.

    Args:
        end: ends a task (the executor then schedules the others).
        reschedule: schedules every task again, with a reason for the log.
        post: runs a job on the executor's worker.
    """

    def __init__(
        self,
        robot: RobotDescription,
        kb: KnowledgeBase,
        *,
        ledger: TaskLedger,
        launcher: Launcher,
        configurator: Configurator,
        supervisor: BehaviorSupervisor,
        faults: Faults,
        end: End,
        reschedule: Callable[[str], None],
        post: Post,
    ) -> None:
        self.robot = robot
        self.kb = kb
        self.ledger = ledger
        self.launcher = launcher
        self.configurator = configurator
        self.supervisor = supervisor
        self.faults = faults
        self._end = end
        self._reschedule = reschedule
        self._post = post
        self._hand_restarts: dict[str, int] = {}  # restarts of behaviors started by hand

    def on_component_state(self, state: ComponentState) -> None:
        """The launcher's listener (its threads): an exit goes to the worker."""
        if state.state in (Lifecycle.EXITED, Lifecycle.FAILED):
            self._post(lambda: self._exited(state))

    def fault(
        self, name: str, reason: str, *, permanent: bool = False, restart: bool = False
    ) -> FaultReply:
        """Count a fault of a component and repair what it hit.

        Args:
            permanent: mark it permanently faulty at once.
            restart: restart it even if no task holds it (a user's or a rule's restart).
        """
        if self.robot.components[name].kind is Kind.BEHAVIOR:
            self._behavior_fault(name, reason, permanent=permanent)
            return self.reply(name)
        running = [t.usage() for t in self.ledger.holding()]
        decision = self.faults.fault(name, reason, running, permanent=permanent)
        self.kb.log_event(
            "REPAIR",
            name,
            {"restart": decision.restart, "unusable": dict(decision.unusable),
             "tasks": {t: a.value for t, a in decision.tasks.items()},
             **({"unavailable": True} if decision.unavailable else {})},
        )  # fmt: skip
        for task_id, action in decision.tasks.items():
            self.supervisor.interrupt(self.ledger.get(task_id), action, name)
        if decision.restart:
            alive = self.configurator.alive(name)
            kept = name in self.configurator.configuration.functionalities
            if kept or self.configurator.by_hand(name) or (restart and alive):
                state = self.configurator.restart(name, "restarting after a fault")
                if state.state is not Lifecycle.READY:
                    return self.fault(name, f"could not restart: {state.reason}")
            for task_id in decision.tasks:
                self.supervisor.go_on(self.ledger.get(task_id))
        else:
            self.configurator.forget_by_hand(name)
            gone = "permanently faulty" if decision.permanent else f"unavailable ({reason})"
            if self.configurator.alive(name):
                self.configurator.stop(name, gone)
            self._reschedule(f"{name} is {gone}")
        return self.reply(name)

    def on_host(self, host: str, connected: bool) -> None:
        """The launcher's host listener: a host agent joined or was lost (its components'
        ends come as their own faults); schedule again on the worker."""

        def changed() -> None:
            placed = self.robot.placed_on(host)
            if connected:  # no longer reported unavailable to the diagnosis engine
                self.configurator.host_back(placed)
            else:  # every functionality we kept there is unavailable now: its tasks move
                kept = [n for n in placed if n in self.robot.functionalities
                        and self.configurator.expects(n)]  # fmt: skip
                for name in kept:  # before the first repair stops the others
                    self.configurator.lost(name)
                for name in kept:
                    self.fault(name, f"its host '{host}' was lost")
            self._reschedule(f"host '{host}' {'joined' if connected else 'was lost'}")

        self._post(changed)

    def warm_restart(self, name: str, reason: str) -> ComponentState:
        """Restart a running component that is not faulty (new parameters): the tasks on
        it are held while it restarts, as during a repair, and go on afterwards; a
        restart that fails is a fault."""
        hit = [t for t in self.ledger.holding() if name in (t.behavior, *t.providers.values())]
        behavior = self.robot.components[name].kind is Kind.BEHAVIOR
        for task in hit:
            reconfigurable = self.robot.behaviors[task.behavior].reconfigurable
            action = TaskAction.PAUSE if reconfigurable and not behavior else TaskAction.RESTART
            self.supervisor.interrupt(task, action, name)
        state = self.configurator.restart(name, reason)
        if state.state is not Lifecycle.READY:
            self.fault(name, f"could not restart: {state.reason}")
            return self.launcher.state(name)
        for task in hit:
            self.supervisor.go_on(task)
        return state

    def reply(self, name: str) -> FaultReply:
        """The component's state with its fault count."""
        record = self.kb.component(name)
        return FaultReply(
            state=self.launcher.state(name),
            faults=record.fault_count,
            permanent=record.permanent_fault,
        )

    def reset(self, name: str) -> list[str]:
        """Clear a component's faults after maintenance; the functionalities usable again."""
        usable = self.faults.reset(name)
        self.kb.log_event("COMPONENT_RESET", name, {"usable": usable})
        self._reschedule(f"{name} was reset")
        return usable

    def started_by_hand(self, name: str) -> None:
        """A user started the component: its restarts count afresh."""
        self._hand_restarts.pop(name, None)

    def _behavior_fault(self, name: str, reason: str, *, permanent: bool) -> None:
        hit = [t for t in self.ledger.holding() if t.behavior == name]
        if permanent:
            self.faults.fault(name, reason, permanent=True)
            self.configurator.forget_by_hand(name)
            for task in hit:
                self._end(task, TaskEnd.BEHAVIOR_FAULTY, f"{name} is permanently faulty: {reason}")
        elif hit:
            self.supervisor.failed(hit[0], reason)
        else:
            self.faults.fault(name, reason)

    def _exited(self, state: ComponentState) -> None:
        name = state.component
        if not self.configurator.expects(name):
            return  # not ours to keep running
        kind = self.robot.components[name].kind
        if kind is Kind.FUNCTIONALITY and name in self.launcher.unavailable():
            return  # its host was lost: on_host counts the faults of all it ran
        why = state.reason or (
            f"exited with code {state.exit_code}"
            if state.signal is None
            else f"killed by signal {state.signal}"
        )
        if kind is Kind.BEHAVIOR:
            if self.configurator.by_hand(name) and not any(
                t.behavior == name for t in self.ledger.holding()
            ):
                self._hand_behavior_exited(name, why)
            return  # a task's behavior: its goal result tells its task
        self.configurator.lost(name)
        self.fault(name, why)

    def _hand_behavior_exited(self, name: str, why: str) -> None:
        """A behavior started by hand, with no task, exited: a fault; restart it up to
        its ``max_restarts``."""
        self.configurator.lost(name)
        decision = self.faults.fault(name, why)
        restarts = self._hand_restarts.get(name, 0)
        again = not decision.permanent and restarts < self.robot.behaviors[name].max_restarts
        self.kb.log_event("REPAIR", name, {"restart": again, "attempt": restarts + 1})
        if not again:
            self.configurator.forget_by_hand(name)
            return
        self._hand_restarts[name] = restarts + 1
        self.configurator.start(name)
