"""The task executor (thesis 5.1.3, 6.1, chapter 7): tasks on scheduled system configurations.

A task asks for the system configuration its behavior needs, with its constraints
(earliest start, deadline, expected duration, tasks to start together with). The
scheduler (:mod:`executive.tasks.scheduler`, clingo) places every waiting and running task at
once; the executor then brings the configuration up (functionalities in dependency
order, shared ones reference-counted, what no task needs any more stopped), starts the
behavior and sends it the task's goal, and supervises it until it succeeds, fails or is
cancelled.

Faults (:mod:`executive.tasks.faults` decides, this module carries out): a functionality
whose process exits, a repair command, or a user's restart counts a fault. Below its
``max_faults`` it is restarted while the behaviors on it pause (reconfigurable) or stop
and start again; at ``max_faults`` it is permanently faulty and the tasks on it are
rescheduled on the remaining providers, or fail with the reason. A failing behavior is
restarted (warm, from its achievements) up to ``max_restarts`` times, then its task
fails.

All decisions happen on one thread that takes work from a queue; the public methods
post to it. Every step is an event in the knowledge base (TASK_*, CONFIGURATION,
FAULT), and the diagnosis model follows the running components (``diagnosis/model``).
"""

from __future__ import annotations

import contextlib
import enum
import itertools
import logging
import threading
import time
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any, TypeVar

from executive.bus.keys import DIAGNOSIS_MODEL, api
from executive.bus.payloads import ComponentState, GoalResult, GoalStatus, Lifecycle
from executive.bus.service import Context, Service
from executive.bus.worker import Worker
from executive.runtime.launcher import GoalHandle, Launcher
from executive.tasks.configuration import SystemConfiguration
from executive.tasks.faults import Faults, TaskAction, TaskUsage
from executive.tasks.schedule import Request
from executive.tasks.scheduler import Scheduler
from knowledge.description import Kind
from knowledge.errors import BusError, ComponentError, DuraError, KnowledgeError
from knowledge.records import TaskState

log = logging.getLogger("dura.task_executor")

T = TypeVar("T")
NOW = 0.15  # a task scheduled to start within this many seconds starts now
MODEL_TIMEOUT = 1.0  # seconds to wait for the diagnosis engine's answer


class TaskPhase(enum.Enum):
    """Where a task is, as the executor sees it."""

    WAITING = "waiting"  # asked for its configuration
    STARTING = "starting"  # configuration and behavior coming up
    RUNNING = "running"
    PAUSED = "paused"
    REPAIRING = "repairing"  # its configuration is being repaired after a fault
    SUCCEEDED = "succeeded"
    FAILED = "failed"
    CANCELLED = "cancelled"

    @property
    def final(self) -> bool:
        return self in (TaskPhase.SUCCEEDED, TaskPhase.FAILED, TaskPhase.CANCELLED)

    @property
    def holds(self) -> bool:
        """It holds a configuration."""
        return self in (
            TaskPhase.STARTING,
            TaskPhase.RUNNING,
            TaskPhase.PAUSED,
            TaskPhase.REPAIRING,
        )


KB_STATE = {
    TaskPhase.WAITING: TaskState.PENDING,
    TaskPhase.STARTING: TaskState.SCHEDULED,
    TaskPhase.RUNNING: TaskState.RUNNING,
    TaskPhase.PAUSED: TaskState.PAUSED,
    TaskPhase.REPAIRING: TaskState.RUNNING,
    TaskPhase.SUCCEEDED: TaskState.SUCCEEDED,
    TaskPhase.FAILED: TaskState.FAILED,
    TaskPhase.CANCELLED: TaskState.CANCELLED,
}

Listener = Callable[["TaskHandle"], None]


@dataclass
class _Task:
    id: str
    name: str  # the action (or the behavior, for a task a user started)
    behavior: str
    goal: dict[str, Any]
    duration: float
    earliest: float  # epoch seconds
    deadline: float | None  # epoch seconds
    together: tuple[str, ...]
    listener: Listener | None
    phase: TaskPhase = TaskPhase.WAITING
    providers: dict[str, str] = field(default_factory=dict)
    handle: GoalHandle | None = None
    attempt: int = 0  # goals sent; a result of an older one is ignored
    began: float | None = None  # when the behavior first ran
    paused_by_user: bool = False
    reason: str = ""
    result: dict[str, Any] | None = None
    done: threading.Event = field(default_factory=threading.Event)
    start_at: float | None = None  # scheduled start (epoch), while waiting
    repair: TaskAction = TaskAction.RESTART  # how it goes on after a repair

    def running_task(self) -> TaskUsage:
        return TaskUsage(self.id, self.behavior, frozenset(self.providers.values()))


class TaskHandle:
    """A task as its requester sees it; methods return at once (the executor acts)."""

    def __init__(self, executor: TaskExecutor, task: _Task) -> None:
        self._executor = executor
        self._task = task

    @property
    def id(self) -> str:
        return self._task.id

    @property
    def phase(self) -> TaskPhase:
        return self._task.phase

    @property
    def reason(self) -> str:
        return self._task.reason

    @property
    def result(self) -> dict[str, Any] | None:
        return self._task.result

    @property
    def providers(self) -> dict[str, str]:
        return dict(self._task.providers)

    def pause(self) -> None:
        self._executor.pause(self.id)

    def resume(self) -> None:
        self._executor.resume(self.id)

    def cancel(self, reason: str = "cancelled") -> None:
        self._executor.cancel(self.id, reason)

    def wait(self, timeout: float | None = None) -> bool:
        """Wait until the task ended; whether it did."""
        return self._task.done.wait(timeout)


class TaskExecutor(Service):
    """Runs tasks on system configurations (see the module docstring).

    Args:
        context: robot, bus and knowledge base.
        launcher: starts and stops the component processes.
        time_limit: seconds one schedule may take.
    """

    name = "task-executor"

    def __init__(self, context: Context, launcher: Launcher, *, time_limit: float = 1.0) -> None:
        super().__init__(context)
        self.launcher = launcher
        self.time_limit = time_limit
        self.robot = context.robot
        self.kb = context.kb
        self._worker = Worker("task executor")
        self._tasks: dict[str, _Task] = {}
        self._configuration = SystemConfiguration()
        self._expected: set[str] = set()  # components we started and keep running
        self._timer: threading.Timer | None = None
        self._declared: list[Any] = []
        self._modelled: set[str] = set()
        self._ids = itertools.count(1)

    # --- lifecycle -----------------------------------------------------------------------

    def start(self) -> None:
        self.faults = Faults(self.robot, self.kb)
        with self.kb.transaction():  # tasks of an executive that died
            for task in self.kb.tasks():
                if not task.state.is_final:
                    reason = "the executive stopped before it ended"
                    self.kb.set_task_state(task.id, TaskState.FAILED, reason=reason)
        self.launcher.add_listener(self._on_component_state)
        self._worker.start()
        bus = self.context.bus
        for verb, handler in self._api().items():
            self._declared.append(bus.serve(api(verb), handler, threaded=True))

    def stop(self) -> None:
        if not self._worker.running:
            return
        for entity in self._declared:
            with contextlib.suppress(Exception):
                entity.undeclare()
        self._declared = []
        self.launcher.remove_listener(self._on_component_state)
        self._call(self._shutdown, timeout=60.0)
        self._worker.stop()

    def _post(self, job: Callable[[], None]) -> None:
        self._worker.post(job)

    def _call(self, fn: Callable[[], T], timeout: float | None = 30.0) -> T:
        """Run ``fn`` on the executor's thread and return its result (or raise)."""
        return self._worker.call(fn, timeout)

    def _shutdown(self) -> None:
        if self._timer is not None:
            self._timer.cancel()
        for task in list(self._tasks.values()):
            if not task.phase.final:
                self._end(task, TaskPhase.CANCELLED, "the executive stops", reschedule=False)
        self._apply_configuration("the executive stops")

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
            DuraError: the robot has no such behavior, or a constraint is invalid.
        """
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
        task = _Task(
            str(record.id), name or behavior, behavior, dict(goal or {}), duration,
            now + earliest, None if deadline is None else now + deadline, together, listener,
        )  # fmt: skip
        handle = TaskHandle(self, task)
        self._post(lambda: self._request(task))
        return handle

    def pause(self, task_id: str) -> None:
        self._call(lambda: self._pause(self._task(task_id)))

    def resume(self, task_id: str) -> None:
        self._call(lambda: self._resume(self._task(task_id)))

    def cancel(self, task_id: str, reason: str = "cancelled") -> None:
        self._post(lambda: self._cancel(task_id, reason))

    def fault(self, name: str, reason: str, *, permanent: bool = False) -> dict[str, Any]:
        """A fault of a component reported by a repair rule or a user (restart / faulty)."""
        self._check_component(name)
        return self._call(lambda: self._fault(name, reason, permanent=permanent, restart=True))

    def reset(self, name: str) -> list[str]:
        """Clear a component's faults after maintenance; the functionalities usable again."""
        self._check_component(name)
        return self._call(lambda: self._reset(name))

    def tasks(self) -> list[dict[str, Any]]:
        """Every task with its phase and configuration (newest last)."""
        return self._call(lambda: [_describe(t) for t in self._tasks.values()])

    def schedule(self) -> dict[str, Any]:
        """The running and waiting tasks in time, and the functionalities each uses."""
        return self._call(self._schedule_view)

    # --- requests and scheduling -----------------------------------------------------------

    def _task(self, task_id: str) -> _Task:
        task = self._tasks.get(str(task_id))
        if task is None:
            raise KnowledgeError(f"no task {task_id}")
        return task

    def _check_component(self, name: str) -> None:
        if name not in self.robot.components:
            known = ", ".join(sorted(self.robot.components))
            raise KnowledgeError(f"robot '{self.robot.name}' has no component '{name}' ({known})")

    def _request(self, task: _Task) -> None:
        self._tasks[task.id] = task
        self._event("TASK_REQUESTED", task, goal=task.goal, duration=task.duration)
        self._reschedule(f"task {task.id} requested")

    def _reschedule(self, why: str) -> None:
        """Schedule every waiting and running task again, and act on the schedule."""
        if self._timer is not None:
            self._timer.cancel()
            self._timer = None
        now = time.time()
        live = [t for t in self._tasks.values() if t.phase.holds or t.phase is TaskPhase.WAITING]
        if not live:
            self._apply_configuration(why)
            return
        requests = []
        for t in live:
            needs = self.robot.behaviors[t.behavior].requires
            if t.phase.holds:
                ran = now - t.began if t.began is not None else 0.0
                remaining = max(self._resolution(), t.duration - ran)
                requests.append(
                    Request(t.id, t.behavior, needs, remaining, running=True,
                            configuration=dict(t.providers))
                )  # fmt: skip
            else:
                deadline = None if t.deadline is None else max(1e-3, t.deadline - now)
                together = tuple(x for x in t.together if x in self._tasks)
                requests.append(
                    Request(t.id, t.behavior, needs, t.duration, max(0.0, t.earliest - now),
                            deadline, together)
                )  # fmt: skip
        scheduler = Scheduler(self.faults.functionalities(), time_limit=self.time_limit)
        result = scheduler.schedule(requests, faulty=self.faults.faulty())
        for task_id, reason in result.cancelled.items():
            task = self._tasks[task_id]
            self._end(
                task, TaskPhase.FAILED, f"cancelled by the scheduler: {reason}", reschedule=False
            )
        later: list[float] = []
        for task_id, assignment in result.assignments.items():
            task = self._tasks[task_id]
            providers = dict(assignment.providers)
            if task.phase.holds:
                if providers != task.providers:
                    self._event("TASK_RECONFIGURED", task, before=task.providers, after=providers)
                    task.providers = providers
            elif any(self._tasks[a].phase.holds for a in assignment.after if a in self._tasks):
                task.start_at = None  # it waits for a running task (that may overrun)
            elif assignment.start <= NOW:
                task.providers = providers
                task.start_at = None
                self._set_phase(task, TaskPhase.STARTING)
                self._event("TASK_SCHEDULED", task, providers=providers)
            else:
                task.start_at = now + assignment.start
                later.append(assignment.start)
        self._apply_configuration(why)
        for task in [t for t in self._tasks.values() if t.phase is TaskPhase.STARTING]:
            self._launch_behavior(task)
        for task in [t for t in self._tasks.values() if t.phase is TaskPhase.REPAIRING]:
            self._continue(task)
        if later:
            self._timer = threading.Timer(
                min(later), lambda: self._post(lambda: self._reschedule("a task is due"))
            )
            self._timer.daemon = True
            self._timer.start()

    def _resolution(self) -> float:
        return 0.1

    def _apply_configuration(self, why: str) -> None:
        """Bring the running functionalities in line with the tasks' configurations."""
        target = SystemConfiguration(
            {t.id: dict(t.providers) for t in self._tasks.values() if t.phase.holds}
        )
        transition = self._configuration.transition(target, self.robot.functionalities.values())
        self._configuration = target
        if transition.empty:
            return
        self.kb.log_event(
            "CONFIGURATION",
            ", ".join(sorted(target.functionalities)) or "nothing",
            {"stop": list(transition.stop), "start": list(transition.start), "why": why},
        )
        for name in transition.stop:
            self._stop_component(name, "no task needs it")
        failed: list[str] = []
        for name in transition.start:
            state = self._start_component(name)
            if state.state is not Lifecycle.READY:
                failed.append(name)
        for name in failed:  # a start that failed is a fault of that component
            self._fault(name, f"could not start: {self.launcher.state(name).reason}")

    def _start_component(self, name: str) -> ComponentState:
        self._expected.add(name)
        state = self.launcher.start(name)
        if state.state is Lifecycle.READY:
            self._model("ADD", name)
        else:
            self._expected.discard(name)
        return state

    def _stop_component(self, name: str, reason: str) -> None:
        self._expected.discard(name)
        self._model("REMOVE", name)
        self.launcher.stop(name, reason)

    # --- behaviors -------------------------------------------------------------------------

    def _launch_behavior(self, task: _Task) -> None:
        """Start the task's behavior on its (ready) configuration and send it the goal."""
        if task.phase is not TaskPhase.STARTING:
            return  # started meanwhile (a nested schedule), or ended
        if not all(
            self.launcher.state(f).state is Lifecycle.READY for f in task.providers.values()
        ):
            return  # a provider is being repaired; the fault handling reschedules
        state = self._start_component(task.behavior)
        if state.state is not Lifecycle.READY:
            self._behavior_failed(task, f"behavior {task.behavior} did not start: {state.reason}")
            return
        try:
            task.attempt += 1
            attempt = task.attempt
            handle = self.launcher.send_goal(task.behavior, task.goal, task_id=int(task.id))
        except ComponentError as e:
            self._behavior_failed(task, str(e))
            return
        task.handle = handle
        handle.add_done_callback(lambda r: self._post(lambda: self._on_result(task, attempt, r)))
        if task.began is None:
            task.began = time.time()
        self._set_phase(task, TaskPhase.PAUSED if task.paused_by_user else TaskPhase.RUNNING)
        if task.paused_by_user:
            with contextlib.suppress(ComponentError):
                self.launcher.pause(task.behavior)
        self._event("TASK_STARTED", task, providers=task.providers, attempt=attempt)

    def _on_result(self, task: _Task, attempt: int, result: GoalResult) -> None:
        if attempt != task.attempt or task.phase.final or task.phase is TaskPhase.REPAIRING:
            return  # an older goal, or one we cancelled ourselves
        if result.status is GoalStatus.SUCCEEDED:
            task.result = dict(result.value)
            self._end(task, TaskPhase.SUCCEEDED, "")
        elif result.status is GoalStatus.CANCELLED:
            self._end(task, TaskPhase.CANCELLED, result.reason or "the behavior cancelled it")
        else:
            self._behavior_failed(task, result.reason or "the behavior failed")

    def _behavior_failed(self, task: _Task, reason: str) -> None:
        decision = self.faults.fault(task.behavior, reason, [task.running_task()])
        action = decision.tasks.get(task.id, TaskAction.FAIL)
        self._event("REPAIR", task, component=task.behavior, action=action.value)
        if action is TaskAction.RESTART:
            self._stop_behavior(task, "restarting after a failure")
            self._set_phase(task, TaskPhase.STARTING)
            self._event("TASK_RESTARTED", task, reason=reason)
            self._launch_behavior(task)
        else:
            self._end(task, TaskPhase.FAILED, reason)

    def _stop_behavior(self, task: _Task, reason: str) -> None:
        task.attempt += 1  # whatever the old goal says now is stale
        if task.handle is not None and not task.handle.done():
            with contextlib.suppress(ComponentError, BusError):
                task.handle.cancel()
        task.handle = None
        self._stop_component(task.behavior, reason)

    def _end(self, task: _Task, phase: TaskPhase, reason: str, *, reschedule: bool = True) -> None:
        """End a task; then (unless the caller goes on scheduling) schedule the others
        before the configuration changes, so that what they share keeps running."""
        if task.phase.final:
            return
        held = task.phase.holds
        task.reason = reason
        if held:
            self._stop_behavior(task, reason or phase.value)
        self._set_phase(task, phase, reason=reason, result=task.result)
        self.faults.finished(task.id)
        self._event(f"TASK_{phase.name}", task, **({"reason": reason} if reason else {}))
        task.done.set()
        if reschedule and not self._stopping():
            self._reschedule(f"task {task.id} {phase.value}")

    def _stopping(self) -> bool:
        return not self._worker.running

    def _pause(self, task: _Task) -> None:
        if task.phase.final:
            raise DuraError(f"task {task.id} has ended ({task.phase.value})")
        if not self.robot.behaviors[task.behavior].interruptible:
            raise DuraError(f"task {task.id} ({task.behavior}) is not interruptible")
        task.paused_by_user = True
        if task.phase is TaskPhase.RUNNING:
            self.launcher.pause(task.behavior)
            self._set_phase(task, TaskPhase.PAUSED)
            self._event("TASK_PAUSED", task)

    def _resume(self, task: _Task) -> None:
        if task.phase.final:
            raise DuraError(f"task {task.id} has ended ({task.phase.value})")
        task.paused_by_user = False
        if task.phase is TaskPhase.PAUSED:
            self.launcher.resume(task.behavior)
            self._set_phase(task, TaskPhase.RUNNING)
            self._event("TASK_RESUMED", task)

    def _cancel(self, task_id: str, reason: str) -> None:
        task = self._tasks.get(str(task_id))
        if task is not None:
            self._end(task, TaskPhase.CANCELLED, reason)

    # --- faults ----------------------------------------------------------------------------

    def _on_component_state(self, state: ComponentState) -> None:
        if state.state in (Lifecycle.EXITED, Lifecycle.FAILED):
            self._post(lambda: self._exited(state))

    def _exited(self, state: ComponentState) -> None:
        name = state.component
        if name not in self._expected or self.robot.components[name].kind is Kind.BEHAVIOR:
            return  # not ours to keep running; a behavior's goal result tells its task
        self._expected.discard(name)
        why = state.reason or (
            f"exited with code {state.exit_code}"
            if state.signal is None
            else f"killed by signal {state.signal}"
        )
        self._fault(name, why)

    def _fault(
        self, name: str, reason: str, *, permanent: bool = False, restart: bool = False
    ) -> dict[str, Any]:
        """Count a functionality's (or behavior's) fault and repair what it hit."""
        component = self.robot.components[name]
        if component.kind is Kind.BEHAVIOR:
            hit = [t for t in self._tasks.values() if t.behavior == name and t.phase.holds]
            if permanent:
                self.faults.fault(name, reason, permanent=True)
                for task in hit:
                    self._end(task, TaskPhase.FAILED, f"{name} is permanently faulty: {reason}")
            elif hit:
                self._behavior_failed(hit[0], reason)
            else:
                self.faults.fault(name, reason)
            return self._fault_reply(name)
        running = [t.running_task() for t in self._tasks.values() if t.phase.holds]
        decision = self.faults.fault(name, reason, running, permanent=permanent)
        self.kb.log_event(
            "REPAIR",
            name,
            {"restart": decision.restart, "unusable": dict(decision.unusable),
             "tasks": {t: a.value for t, a in decision.tasks.items()}},
        )  # fmt: skip
        for task_id, action in decision.tasks.items():
            task = self._tasks[task_id]
            if action is TaskAction.PAUSE and task.phase is TaskPhase.RUNNING:
                with contextlib.suppress(ComponentError):
                    self.launcher.pause(task.behavior)
                self._event("TASK_PAUSED", task, reason=f"{name} is being repaired")
            elif action is TaskAction.RESTART:
                self._stop_behavior(task, f"{name} is being repaired")
            task.repair = action
            self._set_phase(task, TaskPhase.REPAIRING)
        if decision.restart:
            alive = self.launcher.state(name).state.is_alive
            if name in self._configuration.functionalities or (restart and alive):
                self._stop_component(name, "restarting after a fault")
                state = self._start_component(name)
                if state.state is not Lifecycle.READY:
                    return self._fault(name, f"could not restart: {state.reason}")
            for task_id in decision.tasks:
                self._continue(self._tasks[task_id])
        else:
            if self.launcher.state(name).state.is_alive:
                self._stop_component(name, "permanently faulty")
            self._reschedule(f"{name} is permanently faulty")
        return self._fault_reply(name)

    def _fault_reply(self, name: str) -> dict[str, Any]:
        """The component's state payload with its fault count."""
        record = self.kb.component(name)
        return {**self.launcher.state(name).to_payload(), "faults": record.fault_count,
                "permanent": record.permanent_fault}  # fmt: skip

    def _continue(self, task: _Task) -> None:
        """A task whose configuration was repaired goes on: resume or start its behavior."""
        if task.phase is not TaskPhase.REPAIRING:
            return
        if not all(
            self.launcher.state(f).state is Lifecycle.READY for f in task.providers.values()
        ):
            return
        if (
            task.repair is TaskAction.PAUSE
            and self.launcher.state(task.behavior).state is Lifecycle.PAUSED
        ):
            self.launcher.resume(task.behavior)
            self._set_phase(task, TaskPhase.RUNNING)
            self._event("TASK_RESUMED", task, reason="configuration repaired")
            return
        self._set_phase(task, TaskPhase.STARTING)
        self._event("TASK_RESTARTED", task, reason="configuration repaired")
        self._launch_behavior(task)

    def _reset(self, name: str) -> list[str]:
        usable = self.faults.reset(name)
        self.kb.log_event("COMPONENT_RESET", name, {"usable": usable})
        self._reschedule(f"{name} was reset")
        return usable

    # --- bookkeeping -----------------------------------------------------------------------

    def _set_phase(
        self, task: _Task, phase: TaskPhase, *, reason: str = "", result: Any = None
    ) -> None:
        task.phase = phase
        with contextlib.suppress(KnowledgeError):
            self.kb.set_task_state(int(task.id), KB_STATE[phase], reason=reason, result=result)
        if task.listener is not None:
            try:
                task.listener(TaskHandle(self, task))
            except Exception:
                log.exception("task listener failed")

    def _event(self, kind: str, task: _Task, **data: Any) -> None:
        self.kb.log_event(kind, f"task {task.id} {task.name}", {"behavior": task.behavior, **data})

    def _model(self, action: str, name: str) -> None:
        """Tell the diagnosis engine that a component runs (ADD) or not (REMOVE)."""
        if (action == "ADD") == (name in self._modelled):
            return
        component = self.robot.components[name]
        node = {"name": name, "sub_topic": list(component.subscribes),
                "pub_topic": list(component.publishes)}  # fmt: skip
        try:
            reply = self.context.bus.request(
                DIAGNOSIS_MODEL, {"action": action, "nodes": [node]}, timeout=MODEL_TIMEOUT
            )
        except BusError as e:
            log.debug("no diagnosis engine to tell: %s", e)
            return
        if reply.get("ok"):
            if action == "ADD":
                self._modelled.add(name)
            else:
                self._modelled.discard(name)
        else:
            log.info("diagnosis model %s %s refused: %s", action, name, reply.get("error"))

    def _schedule_view(self) -> dict[str, Any]:
        now = time.time()
        rows = []
        for t in self._tasks.values():
            if t.phase.final:
                continue
            start = (t.began or now) - now if t.phase.holds else (t.start_at or now) - now
            rows.append({**_describe(t), "start": round(start, 3),
                         "end": round(start + t.duration, 3)})  # fmt: skip
        return {"tasks": rows, "running": sorted(self._configuration.functionalities),
                "faulty": sorted(self.faults.faulty())}  # fmt: skip

    def _api(self) -> dict[str, Callable[[dict[str, Any]], dict[str, Any]]]:
        def text(request: dict[str, Any], key: str) -> str:
            value = request.get(key)
            if not isinstance(value, str) or not value:
                raise DuraError(f"the request needs a text '{key}', not {value!r}")
            return value

        def start(request: dict[str, Any]) -> dict[str, Any]:
            goal = request.get("goal") or {}
            if not isinstance(goal, dict):
                raise DuraError(f"'goal' must be an object, not {goal!r}")
            times: dict[str, float | None] = {}
            for key in ("duration", "earliest", "deadline"):
                value = request.get(key)
                if value is not None and (not isinstance(value, int | float) or value < 0):
                    raise DuraError(f"'{key}' must be a number of seconds, not {value!r}")
                times[key] = None if value is None else float(value)
            together = request.get("together") or []
            if not isinstance(together, list) or not all(isinstance(t, str) for t in together):
                raise DuraError(f"'together' must be a list of task ids, not {together!r}")
            name = text(request, "task")
            spec = self.robot.tasks.get(name)
            behavior = spec.behavior if spec is not None else name
            handle = self.start_task(
                behavior, goal, name=name, duration=times["duration"],
                earliest=times["earliest"] or 0.0, deadline=times["deadline"],
                together=tuple(together),
            )  # fmt: skip
            return {"id": handle.id, "behavior": behavior}

        def task_verb(verb: str) -> Callable[[dict[str, Any]], dict[str, Any]]:
            def run(request: dict[str, Any]) -> dict[str, Any]:
                task_id = str(request.get("id", ""))
                self._call(lambda: self._task(task_id))
                if verb == "stop":
                    self._call(lambda: self._cancel(task_id, "stopped by the user"))
                elif verb == "pause":
                    self.pause(task_id)
                else:
                    self.resume(task_id)
                return {"task": self._call(lambda: _describe(self._task(task_id)))}

            return run

        return {
            "task/start": start,
            "task/list": lambda r: {"tasks": self.tasks()},
            "task/stop": task_verb("stop"),
            "task/pause": task_verb("pause"),
            "task/resume": task_verb("resume"),
            "schedule/show": lambda r: self.schedule(),
            "component/restart": lambda r: self.fault(
                text(r, "name"), str(r.get("reason") or "restarted by request")
            ),
            "component/fault": lambda r: self.fault(
                text(r, "name"), str(r.get("reason") or "marked faulty"), permanent=True
            ),
            "component/reset": lambda r: {"usable": self.reset(text(r, "name"))},
        }


def _default(params: Mapping[str, Any]) -> float:
    """A behavior's expected duration when the requester names none."""
    value = params.get("duration", 10.0)
    return float(value) if isinstance(value, int | float) and value > 0 else 10.0


def _describe(task: _Task) -> dict[str, Any]:
    return {
        "id": task.id,
        "name": task.name,
        "behavior": task.behavior,
        "goal": task.goal,
        "state": task.phase.value,
        "providers": dict(task.providers),
        "functionalities": sorted(set(task.providers.values())),
        "duration": task.duration,
        "reason": task.reason,
        "result": task.result,
    }
