"""The task executor (thesis 5.1.3, 6.1, chapter 7): tasks on scheduled system configurations.

A task asks for the system configuration its behavior needs, with its constraints
(earliest start, deadline, expected duration, tasks to start together with). The
scheduler (:mod:`executive.tasks.scheduler`, clingo) places every waiting and running
task at once (:mod:`executive.tasks.decisions`); the executor then brings the
configuration up (functionalities in dependency order, shared ones reference-counted,
what no task needs any more stopped; :mod:`executive.tasks.configurator`), starts the
behavior and sends it the task's goal, and supervises it until it succeeds, fails or
is cancelled (:mod:`executive.tasks.supervision`). Faults are counted and repaired by
:mod:`executive.tasks.fault_handling`; the diagnosis model follows the running
components (:mod:`executive.tasks.diagnosis_model`).

This module is the service: one worker thread owns the tasks and runs every step
(:mod:`executive.tasks.enactment`); the public methods post to it, and the bus API
(:mod:`executive.bus.api.tasks`, :mod:`executive.bus.api.parameters`) calls them. Status queries (:meth:`TaskExecutor.tasks`,
:meth:`TaskExecutor.schedule`) answer from a :class:`~executive.tasks.snapshot.Snapshot`
the worker replaces after each job and before each component start, never from the
worker itself. Every step is an
event in the knowledge base (TASK_*, CONFIGURATION, FAULT).
"""

from __future__ import annotations

import contextlib
import threading
import time
from collections.abc import Callable, Mapping, Sequence
from typing import Any, TypeVar

from executive.bus.api.parameters import (
    PARAMETER_GET,
    PARAMETER_LIST,
    PARAMETER_SET,
    ParameterReply,
)
from executive.bus.api.tasks import (
    COMPONENT_FAULT,
    COMPONENT_RESET,
    COMPONENT_RESTART,
    SCHEDULE_SHOW,
    TASK_LIST,
    TASK_PAUSE,
    TASK_RESUME,
    TASK_START,
    TASK_STOP,
    ComponentFault,
    ComponentName,
    FaultReply,
    ResetReply,
    ScheduleReply,
    TaskId,
    TaskReply,
    TasksReply,
    TaskStart,
    TaskStarted,
)
from executive.bus.clock import Clock
from executive.bus.payloads import ComponentState
from executive.bus.reports import ExecutorTask
from executive.bus.service import Context, Service
from executive.bus.worker import Worker
from executive.runtime.launcher import Launcher
from executive.tasks.arguments import check_objects
from executive.tasks.enactment import Enactor
from executive.tasks.snapshot import Snapshot
from executive.tasks.task import Listener, Task, TaskEnd, TaskHandle, TaskPhase
from knowledge.domain import DomainInfo, read_domain
from knowledge.errors import DuraError, KnowledgeError
from knowledge.records import TaskState

T = TypeVar("T")
CALL_TIMEOUT = 30.0  # seconds a command waits for the worker (it may be starting components)
STOP_TIMEOUT = 60.0  # seconds the worker gets to cancel every task and stop their components
HAND_TIMEOUT = 60.0  # seconds a start or stop by hand waits (the worker may be starting others)
WORLD_WAIT = 25.0  # seconds a task asked for by hand waits for a new robot's world (callers: 30)

__all__ = ["Listener", "TaskEnd", "TaskExecutor", "TaskHandle", "TaskPhase"]


class TaskExecutor(Service):
    """Runs tasks on system configurations (see the module docstring).

    Args:
        context: robot, bus and knowledge base.
        launcher: starts and stops the component processes.
        time_limit: seconds one schedule may take.
        linger: seconds a functionality that no task and no upcoming plan step needs
            keeps running before it stops.
        sequential: change configurations one component after another, stopping first
            (by default the new components start all at once, before the old stop).
        clock: robot time (default: this process's): a failed plan step's
            functionalities wait :data:`~executive.tasks.enactment.REPLAN_GRACE` of it
            for the new plan.
    """

    name = "task-executor"

    def __init__(
        self,
        context: Context,
        launcher: Launcher,
        *,
        time_limit: float = 1.0,
        linger: float = 0.0,
        sequential: bool = False,
        clock: Clock | None = None,
    ) -> None:
        super().__init__(context)
        self.launcher = launcher
        self.time_limit = time_limit
        self.linger = linger
        self.sequential = sequential
        self.clock = clock
        self.robot = context.robot
        self.kb = context.kb
        self._worker = Worker("task executor", after_each=self._publish)
        self._enactor: Enactor | None = None
        self._declared: list[Any] = []
        # tasks asked for but not yet taken up by the worker, and the snapshot; the lock
        # keeps a new task from being lost between a request and the worker's next picture
        self._lock = threading.Lock()
        self._arrivals: dict[str, Task] = {}
        self._expected: dict[str, tuple[str, ...]] = {}  # by high level (own, a fleet's)
        self._snapshot = Snapshot()
        self._domain_info: DomainInfo | None = None

    # --- lifecycle -----------------------------------------------------------------------

    def on_activate(self) -> None:
        enactor = self._enactor = Enactor(
            self.context,
            self.launcher,
            self,
            post=self._worker.post,
            publish=self._publish,
            time_limit=self.time_limit,
            linger=self.linger,
            sequential=self.sequential,
            clock=self.clock,
        )
        with self.kb.transaction():  # tasks of an executive that died
            for task in self.kb.tasks(s for s in TaskState if not s.is_final):
                reason = "the executive stopped before it ended"
                self.kb.set_task_state(task.id, TaskState.FAILED, reason=reason)
        self._snapshot = Snapshot(faulty=enactor.faults.faulty())
        self.launcher.add_listener(enactor.repairs.on_component_state)
        self.launcher.add_host_listener(enactor.repairs.on_host)
        self._worker.start()
        if any(f.standby for f in self.robot.functionalities.values()):
            self._worker.post(lambda: enactor.reschedule("warm spares start"))
        self._declared = self._serve()

    def on_deactivate(self) -> None:
        if not self._worker.running:
            return
        for entity in self._declared:
            with contextlib.suppress(Exception):
                entity.undeclare()
        self._declared = []
        enactor = self._running
        self.launcher.remove_listener(enactor.repairs.on_component_state)
        self.launcher.remove_host_listener(enactor.repairs.on_host)
        self._call(enactor.shutdown, timeout=STOP_TIMEOUT)
        self._worker.stop()

    # --- the API -------------------------------------------------------------------------

    def start_task(
        self,
        behavior: str,
        goal: Mapping[str, Any] | None = None,
        *,
        name: str | None = None,
        duration: float | None = None,
        earliest: float = 0.0,
        deadline: float | None = None,
        together: tuple[str, ...] = (),
        listener: Listener | None = None,
        plan_id: int | None = None,
        step: int | None = None,
    ) -> TaskHandle:
        """Ask for a task; returns at once. Times are seconds from now.

        Raises:
            DuraError: the robot has no such behavior, a constraint is invalid, or the
                executor is not started.
        """
        enactor = self._running
        spec = self.robot.behaviors.get(behavior)
        if spec is None:
            known = ", ".join(sorted(self.robot.behaviors)) or "none"
            raise DuraError(f"robot '{self.robot.name}' has no behavior '{behavior}' ({known})")
        duration = duration if duration is not None and duration > 0 else _default(spec.params)
        if earliest < 0 or (deadline is not None and deadline <= 0):
            raise DuraError("earliest start must not be negative, and a deadline must be positive")
        record = self.kb.add_task(
            name or behavior, behavior, dict(goal or {}), plan_id=plan_id, step=step
        )
        now = time.time()
        task = Task(
            str(record.id), name or behavior, behavior, dict(goal or {}), duration,
            now + earliest, None if deadline is None else now + deadline, together, listener,
            plan_id=plan_id,
        )  # fmt: skip
        with self._lock:
            self._arrivals[task.id] = task
            self._snapshot = self._snapshot.adding(task.view())

        def take() -> None:
            with self._lock:
                del self._arrivals[task.id]
            enactor.request(task)

        self._worker.post(take)
        return TaskHandle(self, task)

    def expect(self, behaviors: Sequence[str], source: str = "") -> None:
        """The behaviors of the plan's steps still to come, in order (none: no plan):
        what they need keeps running between the steps. ``source`` tells apart the high
        levels whose steps run here (the robot's own, a fleet's): each one's replace only
        its own. Returns at once."""
        enactor = self._running

        def expect() -> None:
            self._expected[source] = tuple(behaviors)
            enactor.expect(tuple(b for found in self._expected.values() for b in found))

        self._worker.post(expect)

    def pause(self, task_id: str) -> None:
        enactor = self._running
        self._call(lambda: enactor.supervisor.pause(enactor.ledger.get(task_id)))

    def resume(self, task_id: str) -> None:
        enactor = self._running
        self._call(lambda: enactor.supervisor.resume(enactor.ledger.get(task_id)))

    def cancel(self, task_id: str, reason: str = "cancelled") -> None:
        """End a task for its requester (:attr:`TaskEnd.REQUESTER`); returns at once."""
        enactor = self._running
        self._worker.post(lambda: enactor.cancel(task_id, TaskEnd.REQUESTER, reason))

    def fault(self, name: str, reason: str, *, permanent: bool = False) -> FaultReply:
        """A fault of a component reported by a repair rule or a user (restart / faulty)."""
        self._check_component(name)
        enactor = self._running
        return self._call(
            lambda: enactor.repairs.fault(name, reason, permanent=permanent, restart=True)
        )

    def reset(self, name: str) -> list[str]:
        """Clear a component's faults after maintenance; the functionalities usable again."""
        self._check_component(name)
        enactor = self._running
        return self._call(lambda: enactor.repairs.reset(name))

    def start_by_hand(self, name: str) -> ComponentState:
        """Start a component for a user (``dura component start``) and wait until it is
        ready: supervised like the others (its exit is a fault), kept running until a
        stop by hand."""
        self.launcher.kind(name)  # refuses an unknown name, as the launcher words it
        enactor = self._running

        def start() -> ComponentState:
            enactor.repairs.started_by_hand(name)
            return enactor.configurator.start_by_hand(name)

        return self._call(start, timeout=HAND_TIMEOUT)

    def stop_by_hand(self, name: str) -> ComponentState:
        """Stop a component for a user and wait until it is gone.

        Raises:
            DuraError: a task holds it (it stops when no task needs it).
        """
        self.launcher.kind(name)
        enactor = self._running

        def stop() -> ComponentState:
            users = sorted(
                t.id
                for t in enactor.ledger.holding()
                if t.behavior == name or name in t.providers.values()
            )
            if users:
                ids = ", ".join(users)
                raise DuraError(
                    f"'{name}' serves task {ids}: it stops when no task needs it "
                    f"(or stop the task: dura task stop {users[0]})"
                )
            return enactor.configurator.stop_by_hand(name, held=False)

        return self._call(stop, timeout=HAND_TIMEOUT)

    def set_parameter(self, name: str, key: str, value: Any) -> ParameterReply:
        """Change a component's parameter: checked against the description, stored, and
        handed to the component if it runs (by its hook, or by a warm restart).

        Raises:
            DuraError: no such component, or a value of the wrong type (the reason).
        """
        enactor = self._running
        return self._call(lambda: enactor.parameters.set(name, key, value), timeout=HAND_TIMEOUT)

    def tasks(self) -> list[ExecutorTask]:
        """Every task with its phase and configuration (newest last), from the snapshot."""
        return self._snapshot.task_list()

    def schedule(self) -> ScheduleReply:
        """The running and waiting tasks in time, and the functionalities each uses, from
        the snapshot."""
        return self._snapshot.schedule(time.time())

    # --- the worker ----------------------------------------------------------------------

    @property
    def _running(self) -> Enactor:
        if self._enactor is None:
            raise DuraError("the task executor is not started")
        return self._enactor

    def _call(self, fn: Callable[[], T], timeout: float = CALL_TIMEOUT) -> T:
        """Run ``fn`` on the worker and return its result (or raise)."""
        return self._worker.call(fn, timeout)

    def _publish(self) -> None:
        """Take a new snapshot (on the worker: after each job, before each component start)."""
        enactor = self._running
        views = enactor.ledger.views()
        running = enactor.configurator.configuration.functionalities
        faulty = enactor.faults.faulty()
        with self._lock:
            arrived = [t.view() for t in self._arrivals.values()]
            self._snapshot = Snapshot((*views, *arrived), running, faulty)

    def _check_component(self, name: str) -> None:
        if name not in self.robot.components:
            known = ", ".join(sorted(self.robot.components))
            raise KnowledgeError(f"robot '{self.robot.name}' has no component '{name}' ({known})")

    # --- the bus API ---------------------------------------------------------------------

    def _serve(self) -> list[Any]:
        bus = self.context.bus
        enactor = self._running

        def stop(task: Task) -> None:
            enactor.end(task, TaskEnd.USER, "stopped by the user")

        return [
            TASK_START.serve(bus, self._start_request),
            TASK_LIST.serve(bus, lambda _: TasksReply(self.tasks())),
            TASK_STOP.serve(bus, lambda r: self._on_task(r, stop)),
            TASK_PAUSE.serve(bus, lambda r: self._on_task(r, enactor.supervisor.pause)),
            TASK_RESUME.serve(bus, lambda r: self._on_task(r, enactor.supervisor.resume)),
            SCHEDULE_SHOW.serve(bus, lambda _: self.schedule()),
            COMPONENT_RESTART.serve(bus, self._restart_request),
            COMPONENT_FAULT.serve(bus, self._fault_request),
            COMPONENT_RESET.serve(bus, self._reset_request),
            PARAMETER_SET.serve(bus, lambda r: self.set_parameter(r.component, r.key, r.value)),
            PARAMETER_GET.serve(bus, lambda r: enactor.parameters.get(r.component, r.key)),
            PARAMETER_LIST.serve(bus, lambda r: enactor.parameters.list(r.component)),
        ]

    def _start_request(self, request: TaskStart) -> TaskStarted:
        spec = self.robot.tasks.get(request.task)
        behavior = spec.behavior if spec is not None else request.task
        if spec is not None:  # the objects it names must be in the world, of their types
            self._wait_for_world()
            check_objects(spec, request.goal, self._domain(), self.kb.objects())
        handle = self.start_task(
            behavior, request.goal, name=request.label, duration=request.duration,
            earliest=request.earliest or 0.0, deadline=request.deadline,
            together=tuple(request.together),
        )  # fmt: skip
        return TaskStarted(handle.id, behavior)

    def _wait_for_world(self) -> None:
        """Wait (bounded) until the knowledge base holds the robot's world: a new robot's
        objects come from its problem file, which the high level loads while the planner
        warms up, a moment after the executive started."""
        deadline = time.monotonic() + WORLD_WAIT
        while self.robot.problem is not None and time.monotonic() < deadline:
            kb = self.kb
            if kb.objects() or kb.facts() or kb.events(kind="WORLD_SEEDED", limit=1):
                return
            time.sleep(0.05)

    def _domain(self) -> DomainInfo:
        """The domain's signatures, read at the first task asked for by hand (reading
        imports unified-planning, which the executive need not wait for at start)."""
        with self._lock:
            if self._domain_info is None:
                self._domain_info = read_domain(self.robot.domain)
            return self._domain_info

    def _on_task(self, request: TaskId, act: Callable[[Task], None]) -> TaskReply:
        """Act on a task on the worker; the task as it is afterwards."""
        ledger = self._running.ledger

        def run() -> ExecutorTask:
            task = ledger.get(request.id)
            act(task)
            return task.view().status()

        return TaskReply(self._call(run))

    def _restart_request(self, request: ComponentFault) -> FaultReply:
        return self.fault(request.name, request.reason or "restarted by request")

    def _fault_request(self, request: ComponentFault) -> FaultReply:
        return self.fault(request.name, request.reason or "marked faulty", permanent=True)

    def _reset_request(self, request: ComponentName) -> ResetReply:
        return ResetReply(self.reset(request.name))


def _default(params: Mapping[str, Any]) -> float:
    """A behavior's expected duration when the requester names none."""
    value = params.get("duration", 10.0)
    return float(value) if isinstance(value, int | float) and value > 0 else 10.0
