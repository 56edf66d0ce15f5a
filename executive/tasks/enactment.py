"""The task executor's decisions carried out, on its worker thread.

After every change that may move tasks (a request, a task's end, a permanent fault, a
reset, a due start) the :class:`Enactor` asks :func:`~executive.tasks.decisions.decide`,
keeps running what the plan's upcoming steps need and what lingers
(:func:`~executive.tasks.decisions.keep_running`), and carries the decision out in this
order: it ends the tasks the scheduler cancelled,
gives running tasks their new providers, changes the system configuration (a start
that fails is a fault of that component) while the behaviors of the tasks due now
start beside it, sends those behaviors their goals once their configurations are
ready, lets repaired tasks go on, and sets a timer for the next due start. Ending a task
schedules the others before the configuration changes, so what they share keeps
running. The behavior of the plan's next step starts ahead, and one that a step to come
runs again keeps running (``--starts sequential``: a behavior starts only on its ready
configuration, and none ahead). When a plan step's behavior fails (the planner plans
again), the functionalities its task held linger for :data:`REPLAN_GRACE` (robot time):
the new plan's first steps take over those they need without a start, and the rest stops
when the grace ends. The behavior itself stops at once, and a functionality that is
unusable or no longer runs is not kept (one that fails meanwhile is a fault as any
other).

It composes the parts that act: the :class:`~executive.tasks.ledger.TaskLedger`, the
:class:`~executive.tasks.configurator.Configurator`, the
:class:`~executive.tasks.supervision.BehaviorSupervisor` and the
:class:`~executive.tasks.fault_handling.FaultHandler`.
"""

from __future__ import annotations

import time
from collections.abc import Callable

from executive.bus.clock import Clock, system_clock
from executive.bus.service import Context
from executive.bus.timers import Timer, later
from executive.runtime.launcher import Launcher
from executive.tasks.configuration import SystemConfiguration, Transition
from executive.tasks.configurator import Configurator
from executive.tasks.decisions import Decision, decide, keep_running
from executive.tasks.diagnosis_model import DiagnosisModelSync
from executive.tasks.fault_handling import FaultHandler
from executive.tasks.faults import Faults
from executive.tasks.ledger import TaskLedger
from executive.tasks.parameters import RuntimeParameters
from executive.tasks.supervision import BehaviorSupervisor, Post
from executive.tasks.task import Task, TaskControl, TaskEnd, TaskPhase

REPLAN_GRACE = 3.0  # robot seconds a failed plan step's functionalities wait for the new plan
# ends of a plan step's task after which the planner plans again (plan_tasks reports them
# as the step's failure) with its configuration still usable; a task the scheduler
# cancelled had no place for its configuration
REPLANNED = frozenset(
    {
        TaskEnd.BEHAVIOR_FAILED,
        TaskEnd.GOAL_FAILED,
        TaskEnd.BEHAVIOR_CANCELLED,
        TaskEnd.BEHAVIOR_FAULTY,
        TaskEnd.USER,
    }
)


class Enactor:
    """Schedules the tasks and carries the decisions out (worker thread only).

    Registers the robot's components in the knowledge base (:class:`Faults`).

    Args:
        context: robot, bus and knowledge base.
        launcher: starts and stops the component processes.
        control: what the requesters' handles act through.
        post: runs a job on the executor's worker.
        publish: refreshes the executor's snapshot (before each component start).
        time_limit: seconds one schedule may take.
        linger: seconds a functionality no task (and no upcoming step) needs keeps
            running before it stops.
        sequential: change configurations one component after another, stopping first
            (:class:`~executive.tasks.configurator.Configurator`).
        clock: robot time, for :data:`REPLAN_GRACE` (default: this process's).
    """

    def __init__(
        self,
        context: Context,
        launcher: Launcher,
        control: TaskControl,
        *,
        post: Post,
        publish: Callable[[], None],
        time_limit: float = 1.0,
        linger: float = 0.0,
        sequential: bool = False,
        clock: Clock | None = None,
    ) -> None:
        self.robot = context.robot
        self.time_limit = time_limit
        self.linger = linger
        self.clock = clock or system_clock()
        self.standby = True  # keep the warm spares (until the executive stops)
        self._post = post
        self._timer: Timer | None = None
        self.upcoming: tuple[str, ...] = ()  # behaviors of the plan's steps to come
        self._warm: set[str] = set()  # behaviors running for steps to come, with no task
        self._lingering: dict[str, float] = {}  # functionality -> until (epoch seconds)
        self.faults = Faults(context.robot, context.kb, launcher.unavailable)
        self.ledger = TaskLedger(context.kb, control)
        self.configurator = Configurator(
            context.kb,
            launcher,
            DiagnosisModelSync(context.bus, context.robot, post),
            before_start=publish,
            sequential=sequential,
        )
        self.supervisor = BehaviorSupervisor(
            context.robot, ledger=self.ledger, launcher=launcher,
            configurator=self.configurator, faults=self.faults, end=self.end, post=post,
        )  # fmt: skip
        self.repairs = repairs = FaultHandler(
            context.robot, context.kb, ledger=self.ledger, launcher=launcher,
            configurator=self.configurator, supervisor=self.supervisor, faults=self.faults,
            end=self.end, reschedule=self.reschedule, post=post,
        )  # fmt: skip
        self.parameters = RuntimeParameters(
            context.robot, context.kb, launcher, restart=repairs.warm_restart
        )

    def request(self, task: Task) -> None:
        """A new task asks for its configuration."""
        self.ledger.add(task)
        self.reschedule(f"task {task.id} requested")

    def reschedule(self, why: str) -> None:
        """Schedule every waiting and running task again, and act on the schedule."""
        if self._timer is not None:
            self._timer.cancel()
            self._timer = None
        now, running, faulty = time.time(), self.configurator.configuration, self.faults.unusable()
        decision = decide(
            self.ledger.views(),
            running,
            robot=self.robot,
            faulty=faulty,
            ratings=self.faults.ratings(),
            now=now,
            time_limit=self.time_limit,
        )
        self._carry_out(self._keep(decision, running, faulty, now), why)

    def expect(self, behaviors: tuple[str, ...]) -> None:
        """The plan's upcoming steps changed (their behaviors, in order): keep running
        what they need, and no longer what they needed."""
        if behaviors == self.upcoming:
            return
        self.upcoming = behaviors
        self._warm_up()
        running = self.configurator.configuration
        if not running.reserved:
            return  # nothing reserved: the next schedule takes them into account
        now, faulty = time.time(), self.faults.unusable()
        kept = self._keep(Decision(configuration=SystemConfiguration(running.tasks)), running,
                          faulty, now)  # fmt: skip
        self._apply(kept.configuration, kept.transition, "the plan's upcoming steps changed")

    def _warm_up(self) -> None:
        """Behaviors for the plan's steps to come: the next step's starts now, while the
        steps before it run (unless components start sequentially); one that runs with no
        task keeps running while a step to come needs it, and stops once none does."""
        held = {t.behavior for t in self.ledger.holding()}
        kept = {b for b in self.upcoming if b in self._warm}
        following = set() if self.configurator.sequential else set(self.upcoming[:1])
        wanted = (kept | following) - self.faults.unusable()
        for name in sorted(self._warm - wanted - held):
            self._warm.discard(name)
            self.configurator.release(name, "no step to come needs it", wait=False)
        for name in sorted(wanted - held - self._warm):
            self._warm.add(name)
            self.configurator.start_soon(name, self._post)

    def _keep(
        self, decision: Decision, running: SystemConfiguration, faulty: frozenset[str], now: float
    ) -> Decision:
        """The decision with what upcoming steps need and what lingers kept running;
        functionalities it would stop start to linger (if they linger at all)."""

        def keep(lingering: set[str]) -> Decision:
            return keep_running(decision, running, robot=self.robot, faulty=faulty,
                                upcoming=self.upcoming, lingering=lingering,
                                standby=self.standby)  # fmt: skip

        needed = keep(set())
        for f in list(self._lingering):
            if f in needed.configuration.functionalities or f not in running.functionalities:
                del self._lingering[f]  # needed again, or it stopped
        if self.linger > 0:
            released = running.functionalities - needed.configuration.functionalities
            for f in released - self._lingering.keys():  # needed until now: it starts to linger
                self._lingering[f] = now + self.linger
        if not self._lingering:
            return needed
        return keep({f for f, until in self._lingering.items() if until > now})

    def _await_replan(self, task: Task) -> None:
        """A plan step's task failed and the planner plans again: what it held lingers
        for the grace (or longer, if functionalities linger longer), for the new plan's
        first steps to take over; what is faulty or no longer runs is not kept."""
        until = time.time() + max(self.clock.wall(REPLAN_GRACE), self.linger)
        unusable = self.faults.unusable()
        for f in set(task.providers.values()) - unusable:
            if self.configurator.alive(f):
                self._lingering[f] = max(self._lingering.get(f, 0.0), until)

    def end(self, task: Task, end: TaskEnd, reason: str, *, reschedule: bool = True) -> None:
        """End a task; then (unless the caller goes on scheduling) schedule the others."""
        if task.phase.final:
            return
        phase = end.phase
        task.reason, task.end = reason, end
        if task.phase.holds:
            # a behavior that achieved its goal and runs a step to come keeps running
            keep = end is TaskEnd.SUCCEEDED and task.behavior in self.upcoming
            self.supervisor.stop(task, reason or phase.value, keep=keep)
            if keep:
                self._warm.add(task.behavior)
            elif task.plan_id is not None and end in REPLANNED:
                self._await_replan(task)
        self.ledger.set_phase(task, phase, reason=reason, result=task.result)
        self.faults.finished(task.id)
        self.ledger.event(f"TASK_{phase.name}", task, **({"reason": reason} if reason else {}))
        task.done.set()
        if reschedule:
            self.reschedule(f"task {task.id} {phase.value}")

    def cancel(self, task_id: str, end: TaskEnd, reason: str) -> None:
        """End a task if there is one of that id."""
        task = self.ledger.find(task_id)
        if task is not None:
            self.end(task, end, reason)

    def shutdown(self) -> None:
        """Cancel every task and stop what they held."""
        for task in self.ledger:
            self.end(task, TaskEnd.SHUTDOWN, "the executive stops", reschedule=False)
        self.upcoming, self.linger, self.standby = (), 0.0, False  # keep nothing running
        self._lingering.clear()
        self._warm_up()
        self.reschedule("the executive stops")  # no task left: everything stops, no timer
        self.configurator.model.close()

    def _carry_out(self, decision: Decision, why: str) -> None:
        for task_id, why_not in decision.cancelled.items():
            task = self.ledger.get(task_id)
            reason = f"cancelled by the scheduler: {why_not}"
            self.end(task, TaskEnd.UNSCHEDULABLE, reason, reschedule=False)
        for task_id, providers in decision.reconfigured.items():
            task = self.ledger.get(task_id)
            self.ledger.event("TASK_RECONFIGURED", task, before=task.providers, after=providers)
            task.providers = dict(providers)
        for task_id in decision.behind_running:
            waiting = self.ledger.get(task_id)  # it waits for a running task, not a time
            waiting.start_at, waiting.behind = None, decision.behind.get(task_id, ())
        for task_id, start in decision.start_later.items():
            self.ledger.get(task_id).start_at, self.ledger.get(task_id).behind = start, ()
        for task_id, providers in decision.start_now.items():
            task = self.ledger.get(task_id)
            task.providers, task.start_at = dict(providers), None
            self.ledger.set_phase(task, TaskPhase.STARTING)
            self.ledger.event("TASK_SCHEDULED", task, providers=task.providers)
        if not self.configurator.sequential:  # a behavior starts with its configuration
            for task in self.ledger.in_phase(TaskPhase.STARTING):
                if not self.configurator.alive(task.behavior):
                    self.configurator.start_soon(task.behavior, self._post)
        self._apply(decision.configuration, decision.transition, why)
        # what is due now, from the tasks as they are: a fault while the configuration
        # changed may have scheduled them again meanwhile
        for task in self.ledger.in_phase(TaskPhase.STARTING):
            self.supervisor.launch(task)
        for task in self.ledger.in_phase(TaskPhase.REPAIRING):
            self.supervisor.go_on(task)
        lingers = [until for f, until in self._lingering.items()
                   if f in decision.configuration.functionalities]  # fmt: skip
        wake = min([*lingers, *([] if decision.wake is None else [decision.wake])], default=None)
        if wake is not None:
            self._timer = later(
                wake - time.time(),
                lambda: self._post(lambda: self.reschedule("a task is due, or a linger ended")),
            )

    def _apply(self, target: SystemConfiguration, transition: Transition, why: str) -> None:
        failed = self.configurator.apply(target, transition, why)
        for name, reason in failed.items():  # a start that failed is a fault of that component
            self.repairs.fault(name, f"could not start: {reason}")
