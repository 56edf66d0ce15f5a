"""The executive process: its bus (listening), knowledge base, launcher and services
(monitoring, diagnosis, repair rules, task executor, high level).

The bus API answers first: as soon as the bus listens and the knowledge base is open,
the high level recovers from a crash, serves its verbs (``status`` among them) and
warms its planner up in the background; only then are the other services' modules
imported and the services started, in order (and stopped in reverse). The high level
begins planning once all of them run. The launcher stops every component when the
executive closes. While it runs, the executive holds the liveliness token
``alive/executive``: components end themselves when it vanishes.

The monitoring services (observers, diagnosis, repair rules) talk to the rest only over
the bus, so they can also run in a process of their own (``dura run --only
monitoring``, :class:`ServiceProcess`), beside an executive that runs without them
(``dura run --without monitoring``). So can the high level (``--only planning``: goals,
planner, plan executor and their verbs, ``status`` among them): it runs its plans'
steps on the executive's task executor over the bus (:mod:`executive.bus.api.steps`).
And so can the task executor with the launcher (``--only tasks``: the components of the
executive's computer, their verbs and resource monitor, and the plan steps the high
level asks for over the bus).
"""

from __future__ import annotations

import contextlib
import dataclasses
import os
import threading
from collections.abc import Callable, Collection, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

from executive.bus import security
from executive.bus.clock import system_clock
from executive.bus.keys import EVENTS, EXECUTIVE_ALIVE, service_alive
from executive.bus.service import Context, Service
from executive.bus.session import Bus, connect_when_there
from executive.planning.high_level import HighLevel
from executive.runtime.run_lock import RunLock, end_leftovers
from knowledge.description import RobotDescription
from knowledge.errors import ConfigError, DuraError
from knowledge.knowledge_base import KnowledgeBase
from knowledge.records import to_plain

if TYPE_CHECKING:
    from executive.bus.reports import ComponentEntry, ExecutorTask
    from executive.bus.topic_source import TopicSource
    from executive.planning.bus_tasks import BusTasks
    from executive.planning.task_runner import TaskRunner
    from executive.ros2.link import Ros2Link
    from executive.runtime.launcher import Launcher
    from executive.tasks.executor import TaskExecutor
    from executive.tasks.plan_tasks import PlanTasks


MONITORING = "monitoring"
PLANNING = "planning"
TASKS = "tasks"
SEPARABLE = (MONITORING, PLANNING, TASKS)
"""The groups of services that can run in a process of their own."""

SIGNAL_POLL = 0.1  # seconds: the longest a pending Ctrl-C or SIGTERM waits for its handler


def separable(group: str) -> str:
    """``group`` if it names a group of services that can run apart.

    Raises:
        ConfigError: it does not.
    """
    if group not in SEPARABLE:
        raise ConfigError(f"no group of services {group!r} (groups: {', '.join(SEPARABLE)})")
    return group


def relay_events(kb: KnowledgeBase, bus: Bus) -> None:
    """Publish every event this process logs on the ``events`` topic, as the high level
    does for its own process (a process without one needs this)."""
    kb.add_listener(lambda event: bus.publish(EVENTS, to_plain(event)))


def ros2_link(robot: RobotDescription, group: str | None = None) -> Ros2Link:
    """The robot's ROS 2 link (the robot has a ``ros2:`` section): the executive's, or
    that of a group of services in a process of its own, whose node is named after the
    group (``dura_monitoring``) so that ROS 2 tools tell the two apart."""
    from executive.ros2.link import Ros2Link

    spec = robot.ros2
    if spec is None:
        raise ConfigError(f"robot '{robot.name}' has no ros2 section")
    if group is not None:
        spec = dataclasses.replace(spec, node=f"{spec.node}_{group}")
    nodes = {c.ros2.node: name for name, c in robot.components.items()
             if c.ros2 is not None and c.ros2.node is not None}  # fmt: skip
    return Ros2Link(spec, nodes=nodes)


def remote_status(bus: Bus) -> dict[str, Callable[[], Any]]:
    """The sections of ``status`` that a task executor in another process answers."""
    from executive.bus.api.components import COMPONENT_LIST
    from executive.bus.api.tasks import TASK_LIST

    return {
        "tasks": lambda: TASK_LIST.call(bus).tasks,
        "components": lambda: COMPONENT_LIST.call(bus).components,
    }


def bus_tasks(robot: RobotDescription, bus: Bus, server: str) -> BusTasks:
    """The plan steps of a high level, run by the task executor of the process that holds
    the liveliness token ``server``."""
    from executive.planning.bus_tasks import BusTasks

    return BusTasks(
        bus,
        {action: robot.behaviors[spec.behavior].interruptible
         for action, spec in robot.tasks.items() if spec.behavior in robot.behaviors},
        server,
    )  # fmt: skip


def launcher(
    context: Context, log_dir: Path, grace: float, credentials: security.Credentials, run_id: str
) -> Launcher:
    """The launcher of the components placed on this computer (and of the host agents')."""
    from executive.runtime.launcher import Launcher

    return Launcher(
        context.robot,
        context.bus,
        context.kb,
        log_dir=log_dir,
        grace=grace,
        credentials=credentials,
        run_id=run_id,
    )


def component_services(
    context: Context, launcher: Launcher, tasks: TaskExecutor, resource_rate: float
) -> list[Service]:
    """The verbs of the components this process launches, and their resource monitor."""
    from executive.runtime.component_api import ComponentApi
    from monitoring.resource_monitor import ResourceMonitor

    return [
        ComponentApi(context, launcher, by_hand=tasks),
        ResourceMonitor(  # host agents measure the components they run themselves
            context, rate=resource_rate, components=context.robot.placed_on(None)
        ),
    ]


def monitoring_services(context: Context, sources: Sequence[TopicSource] = ()) -> list[Service]:
    """The observers, the diagnosis engine and the repair rules, in the order they start."""
    from monitoring.diagnosis.diagnosis_service import DiagnosisService
    from monitoring.observer_manager import ObserverManager
    from monitoring.repair.rule_service import RuleService

    return [
        ObserverManager(context, sources=list(sources)),
        DiagnosisService(context, learn=True),
        RuleService(context),
    ]


class Executive:
    """Everything the executive process runs, opened and closed together.

    Args:
        robot: the robot to run.
        endpoint: where to listen (default: the robot's bus endpoint).
        kb_path: the knowledge base (default: the robot's, ``./.dura/<robot>.db``).
        log_dir: where component logs go (default ``./.dura/logs``).
        resource_rate: how often the resource monitor publishes, in Hz.
        grace: seconds a component gets at each step of a stop.
        linger: seconds a functionality no task and no upcoming plan step needs keeps
            running before it stops.
        sequential_starts: change configurations one component after another, stopping
            first (by default: all at once, before the old ones stop).
        folder: the working folder whose ``.dura/`` holds the bus credentials (created on
            the first run, user-only) and the logs (default: the current folder).
        record: record the bus traffic to this MCAP file (``dura run --record``).
        record_max_size: bytes at which the recording is rotated (default: the recorder's).
        on_failure: called with the reason when the executive cannot go on (its domain
            does not fit the robot: checked while it runs, see
            :class:`~executive.planning.high_level.HighLevel`); ``dura run`` stops then.
        on_open: called once the bus API answers, before the other services start
            (``dura run`` writes its run file then, for the commands run beside it).
        progress: told what the executive does now while it starts (``dura run``'s
            live line on a terminal).
        without: groups of services (:data:`SEPARABLE`) another process runs.
    """

    def __init__(
        self,
        robot: RobotDescription,
        *,
        endpoint: str | None = None,
        kb_path: Path | None = None,
        log_dir: Path | None = None,
        resource_rate: float = 1.0,
        grace: float = 3.0,
        folder: Path | None = None,
        linger: float = 0.0,
        sequential_starts: bool = False,
        record: Path | None = None,
        record_max_size: int | None = None,
        on_failure: Callable[[str], None] | None = None,
        on_open: Callable[[], None] | None = None,
        progress: Callable[[str], None] | None = None,
        without: Collection[str] = (),
    ) -> None:
        for group in without:
            separable(group)
        self.robot = robot
        self.without = frozenset(without)
        self.endpoint = endpoint or robot.endpoint
        self.kb_path = kb_path or robot.kb_path()
        self.folder = folder or Path.cwd()
        self.log_dir = log_dir or self.folder / ".dura" / "logs"
        self.credentials_path = security.credentials_file(self.folder, robot.name)
        self.resource_rate = resource_rate
        self.grace = grace
        self.linger = linger
        self.sequential_starts = sequential_starts
        self.record = record
        self.record_max_size = record_max_size
        self.on_failure = on_failure
        self.on_open = on_open
        self.progress = progress or (lambda _: None)
        self.tasks: TaskExecutor | None = None
        self.launcher: Launcher | None = None
        self._stack = contextlib.ExitStack()

    def __enter__(self) -> Executive:
        clock = system_clock()  # a bad DURA_TIME_SCALE stops the executive here, with why
        with contextlib.ExitStack() as stack:
            self.progress("taking the knowledge base's run lock")
            lock = stack.enter_context(RunLock(self.kb_path))  # one executive per KB
            if lock.predecessor is not None:
                end_leftovers(lock.predecessor)
            robot, components = self.robot, list(self.robot.components)
            credentials = security.ensure_credentials(
                self.credentials_path, robot.name, components, robot.hosts
            )
            security.write_host_credentials(credentials, self.folder, robot.hosts)
            users = self.credentials_path.with_suffix(".users")
            self.progress(f"opening the bus on {self.endpoint}")
            self.bus = stack.enter_context(
                Bus(
                    robot.name,
                    name="executive",
                    endpoint=self.endpoint,
                    listen=True,
                    login=credentials.login(security.EXECUTIVE),
                    dictionary=security.dictionary(credentials, users),
                    access=security.access_control(robot.name, components, robot.hosts),
                )
            )
            self.progress(f"opening the knowledge base {self.kb_path}")
            self.kb = stack.enter_context(KnowledgeBase(self.kb_path))
            self.kb.log_event(
                "EXECUTIVE_STARTED",
                self.robot.name,
                {"endpoint": self.endpoint, "pid": os.getpid(), "time_scale": clock.scale},
            )
            stack.callback(self.kb.log_event, "EXECUTIVE_STOPPED", self.robot.name)
            context = Context(self.robot, self.bus, self.kb)
            self.high_level: HighLevel | None = None
            if PLANNING in self.without:  # the high level relays the events otherwise
                relay_events(self.kb, self.bus)
            else:
                runner: TaskRunner | Callable[[], TaskRunner] = self._plan_tasks
                status = {"tasks": self._tasks, "components": self._components}
                if TASKS in self.without:  # the task executor of the tasks process
                    runner = bus_tasks(robot, self.bus, service_alive(TASKS))
                    stack.callback(runner.close)
                    status = remote_status(self.bus)
                self.high_level = HighLevel(
                    context, runner, status=status, on_failure=self.on_failure
                )
                self.high_level.open()  # the API answers from here on
                stack.callback(self.high_level.stop)  # if a later start fails
            if self.on_open is not None:
                self.on_open()
            if TASKS not in self.without:
                self.progress("loading the launcher")
                self.launcher = stack.enter_context(
                    launcher(context, self.log_dir, self.grace, credentials, lock.run_id)
                )
            self.ros2: Ros2Link | None = None
            if self.robot.ros2 is not None:  # Cyclone DDS loads only for a ROS 2 robot
                self.progress("joining the ROS 2 domain")
                self.ros2 = stack.enter_context(ros2_link(self.robot))
                if self.high_level is not None:
                    self.high_level.sources = (self.ros2.topics,)  # before it starts sensing
            self.progress("loading the services")
            for service in self.services(context):
                self.progress(f"starting the {service.name} service")
                service.start()
                stack.callback(service.stop)
            self.bus.declare_alive(EXECUTIVE_ALIVE)
            self._stack = stack.pop_all()
        return self

    def services(self, context: Context) -> list[Service]:
        """The services of the executive, in the order they start (and stop reversed):
        monitoring first, so that it watches every component the executive starts; the
        high level last (its API answers already: it begins planning)."""
        from executive.tasks.executor import TaskExecutor

        launched: list[Service] = []
        if self.launcher is not None:
            self.tasks = TaskExecutor(
                context, self.launcher, linger=self.linger, sequential=self.sequential_starts
            )
            launched = component_services(context, self.launcher, self.tasks, self.resource_rate)
        ros2 = self.ros2
        extra: list[Service] = []
        last: list[Service] = []
        if ros2 is not None:
            from executive.ros2.goal_topic import Ros2Goals
            from executive.ros2.graph_model import Ros2GraphModel
            from executive.ros2.state import Ros2StatePublisher

            extra.append(Ros2StatePublisher(context, ros2.spec, link=ros2))
            extra.append(Ros2GraphModel(context, ros2.discovery))
            last.append(Ros2Goals(context, ros2))  # once the high level takes goals
        recording: list[Service] = []
        if self.record is not None:  # first: it sees every other service's traffic
            from executive.bags.recording import DEFAULT_MAX_SIZE, Recording

            size = self.record_max_size or DEFAULT_MAX_SIZE
            recording.append(Recording(context, self.record, max_size=size))
        return [
            *recording,
            *launched,
            *(
                monitoring_services(context, [ros2.topics] if ros2 is not None else [])
                if MONITORING not in self.without
                else []
            ),
            *extra,
            *([self.tasks] if self.tasks is not None else []),
            *self._planning(context),
            *last,
        ]

    def _planning(self, context: Context) -> list[Service]:
        """The high level, or the task executor's side of the plan steps that the high
        level of another process asks for (``--without planning``)."""
        if self.high_level is not None:
            return [self.high_level]
        if self.tasks is None:  # the tasks process serves the steps
            return []
        from executive.tasks.step_service import StepService

        return [StepService(context, self.tasks)]

    def _plan_tasks(self) -> PlanTasks:
        """The task executor as the high level's runner of plan steps (once it runs)."""
        from executive.tasks.plan_tasks import PlanTasks

        if self.tasks is None:
            raise DuraError("the task executor has not started")
        return PlanTasks(self.tasks, self.robot)

    def _tasks(self) -> list[ExecutorTask]:
        if self.tasks is None:
            raise DuraError("the task executor is starting")
        return self.tasks.tasks()

    def _components(self) -> list[ComponentEntry]:
        if self.launcher is None:
            raise DuraError("the launcher is starting")
        from executive.runtime.component_api import listed

        return [listed(self.launcher, s) for s in self.launcher.states()]

    def __exit__(self, *exc: object) -> None:
        self._stack.close()


class ServiceProcess:
    """A group of the executive's services in a process of their own (``dura run --only
    GROUP``): connected to the executive's bus as the trusted user ``service``, with the
    robot's knowledge base (which the executive holds the lock of).

    The ``tasks`` group launches the components of the executive's computer: it runs in
    the executive's folder (the components' bus credentials are there), holds a run lock
    of its own on the knowledge base (``<database>.tasks.lock``: one such process at a
    time, and the next one ends what a killed one left), and its components end with it.

    Args:
        robot: the robot.
        group: which services (:data:`SEPARABLE`).
        endpoint: the executive's endpoint (default: the robot's).
        kb_path: the knowledge base (default: the robot's).
        folder: the working folder whose ``.dura/`` holds the bus credentials.
        say: told one line at each change, for the operator.
        log_dir, resource_rate, grace, linger, sequential_starts: for ``tasks``, as for
            :class:`Executive`.
    """

    def __init__(
        self,
        robot: RobotDescription,
        group: str,
        *,
        endpoint: str | None = None,
        kb_path: Path | None = None,
        folder: Path | None = None,
        say: Callable[[str], None] = lambda line: None,
        log_dir: Path | None = None,
        resource_rate: float = 1.0,
        grace: float = 3.0,
        linger: float = 0.0,
        sequential_starts: bool = False,
    ) -> None:
        self.robot = robot
        self.group = separable(group)
        self.endpoint = endpoint or robot.endpoint
        self.kb_path = kb_path or robot.kb_path()
        self.folder = folder or Path.cwd()
        self._say = say
        self.log_dir = log_dir or self.folder / ".dura" / "logs"
        self.resource_rate = resource_rate
        self.grace = grace
        self.linger = linger
        self.sequential_starts = sequential_starts

    def run(self, stop: threading.Event) -> None:
        """Serve until ``stop`` is set (waiting first, if need be, for the executive).

        Raises:
            BusError: the credentials are there but unusable (or missing, for ``tasks``).
            KnowledgeError: another tasks process runs on the knowledge base.
        """
        with contextlib.ExitStack() as stack:
            lock = None
            if self.group == TASKS:  # before waiting: a second one is refused at once
                lock = stack.enter_context(RunLock(self.kb_path, TASKS))
                if lock.predecessor is not None:
                    end_leftovers(lock.predecessor)
            bus = self._connect(stop)
            if bus is None:
                return
            stack.callback(bus.close)
            kb = stack.enter_context(KnowledgeBase(self.kb_path))
            if self.group != PLANNING:
                # what these services log (rule firings, task ends, ...) is on the bus, as
                # the executive's own events are: for the high level, dura events
                # --follow, the dashboard, the recorder (a high level relays its own)
                relay_events(kb, bus)
            context = Context(self.robot, bus, kb)
            services = (
                self._services(context, stack, stop)
                if lock is None
                else self._task_services(context, stack, lock.run_id)
            )
            for service in services:
                service.start()
                stack.callback(service.stop)
            bus.declare_alive(service_alive(self.group))  # who runs the group, for all to see
            self._say("runs")
            while not stop.wait(SIGNAL_POLL):  # in slices: see executive.cli.stopping
                pass

    def _connect(self, stop: threading.Event) -> Bus | None:
        """The bus, once the executive is there (``None``: stopped before)."""

        def connect() -> Bus:
            # read each time: the executive writes the credentials on its first run
            login = security.find_login(self.robot.name, security.SERVICE, [self.folder])
            return Bus(self.robot.name, name=self.group, endpoint=self.endpoint, login=login)

        return connect_when_there(connect, self.endpoint, stop, self._say)

    def _services(
        self, context: Context, stack: contextlib.ExitStack[Any], stop: threading.Event
    ) -> list[Service]:
        """The monitoring or planning group's services, in the order they start."""
        bus = context.bus
        sources: list[TopicSource] = []
        reads_topics = self.group == MONITORING or self.robot.sensing
        if self.robot.ros2 is not None and reads_topics:  # observers, sensing rules
            sources.append(stack.enter_context(ros2_link(self.robot, self.group)).topics)
        if self.group == MONITORING:
            return monitoring_services(context, sources)
        runner = bus_tasks(self.robot, bus, EXECUTIVE_ALIVE)
        stack.callback(runner.close)

        def failed(reason: str) -> None:
            self._say(f"stops: {reason}")
            stop.set()

        return [
            HighLevel(
                context, runner, status=remote_status(bus), on_failure=failed, sources=sources
            )
        ]

    def _task_services(
        self, context: Context, stack: contextlib.ExitStack[Any], run_id: str
    ) -> list[Service]:
        """The tasks group's services (``run_id``: its run lock's, which marks the
        processes it starts)."""
        from executive.tasks.executor import TaskExecutor
        from executive.tasks.step_service import StepService

        # each component's login: the tasks process runs in the executive's folder
        credentials = security.read_credentials(
            security.credentials_file(self.folder, self.robot.name)
        )
        running = stack.enter_context(
            launcher(context, self.log_dir, self.grace, credentials, run_id)
        )
        tasks = TaskExecutor(
            context, running, linger=self.linger, sequential=self.sequential_starts
        )
        return [
            *component_services(context, running, tasks, self.resource_rate),
            tasks,
            StepService(context, tasks),
        ]
