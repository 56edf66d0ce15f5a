"""The executive process: its bus (listening), knowledge base, launcher and services
(monitoring, diagnosis, repair rules, task executor, high level).

The services are built by group (:mod:`executive.service_groups`) and driven together
by a :class:`~executive.bus.lifecycle_manager.LifecycleManager`: all configured in order,
then all activated in order; deactivated, then shut down, in reverse. The bus API
answers first: the high level is built and configured before the other services are
even loaded (configured, it recovers from a crash, serves its verbs, ``status`` among
them, and warms its planner up in the background); then the launcher opens and the other
services are loaded and configured; then they start (monitoring first, so that it
watches every component the task executor starts), and the high level, last, begins
planning. The launcher stops every
component when the executive closes. While it runs, the executive holds the liveliness
token ``alive/executive``: components end themselves when it vanishes.

The monitoring services (observers, diagnosis, repair rules) talk to the rest only over
the bus, so they can also run in a process of their own (``dura run --only
monitoring``, :class:`ServiceProcess`), beside an executive that runs without them
(``dura run --without monitoring``). So can the high level (``--only planning``: goals,
planner, plan executor and their verbs, ``status`` among them): it runs its plans'
steps on the executive's task executor over the bus (:mod:`executive.bus.api.steps`).
And so can the task executor with the launcher (``--only tasks``: the components of the
executive's computer, their verbs and resource monitor, and the plan steps the high
level asks for over the bus). Both kinds of process build a group with the same builder.
Wherever the task executor runs, it serves plan steps over the bus, also beside the
executive's own high level: a fleet's high level (``dura fleet run``, logged in as the
``fleet`` role) runs its steps for this robot there.
"""

from __future__ import annotations

import contextlib
import functools
import os
import threading
from collections.abc import Callable, Collection
from pathlib import Path
from typing import TYPE_CHECKING, Any

from executive.bus import security
from executive.bus.clock import system_clock
from executive.bus.event_relay import EventRelay
from executive.bus.keys import EXECUTIVE_ALIVE, service_alive
from executive.bus.lifecycle_manager import LifecycleManager
from executive.bus.service import Context, Service
from executive.bus.session import Bus, connect_when_there
from executive.runtime.run_lock import RunLock, end_leftovers
from executive.service_groups import (
    StatusSections,
    TaskSettings,
    TasksGroup,
    bus_tasks,
    launcher,
    monitoring_group,
    planning_group,
    recording_group,
    remote_status,
    ros2_group,
    ros2_link,
    tasks_group,
)
from knowledge.description import RobotDescription
from knowledge.errors import ConfigError, DuraError
from knowledge.knowledge_base import KnowledgeBase

if TYPE_CHECKING:
    from executive.bus.topic_source import TopicSource
    from executive.planning.high_level import HighLevel
    from executive.planning.task_runner import TaskRunner
    from executive.ros2.link import Ros2Link
    from executive.runtime.launcher import Launcher
    from executive.tasks.executor import TaskExecutor


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
        record_flush: seconds between two whole chunks of the recording on disk (default:
            the recorder's, 1 s).
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
        record_flush: float | None = None,
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
        self.settings = TaskSettings(
            log_dir or self.folder / ".dura" / "logs", resource_rate, grace, linger,
            sequential_starts,
        )  # fmt: skip
        self.credentials_path = security.credentials_file(self.folder, robot.name)
        self.record = record
        self.record_max_size = record_max_size
        self.record_flush = record_flush
        self.on_failure = on_failure
        self.on_open = on_open
        self.progress = progress or (lambda _: None)
        self.tasks: TaskExecutor | None = None
        self.launcher: Launcher | None = None
        self.high_level: HighLevel | None = None
        self.ros2: Ros2Link | None = None
        self._tasks_group: TasksGroup | None = None
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
            security.write_fleet_credentials(credentials, self.folder)
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
                    access=security.access_control(
                        robot.name, components, robot.hosts, topics=security.topics_of(robot)
                    ),
                )
            )
            self.progress(f"opening the knowledge base {self.kb_path}")
            self.kb = stack.enter_context(KnowledgeBase(self.kb_path))
            lock.hold_file()  # a new knowledge base is a file now
            self.kb.log_event(
                "EXECUTIVE_STARTED",
                self.robot.name,
                {"endpoint": self.endpoint, "pid": os.getpid(), "time_scale": clock.scale},
            )
            stack.callback(self.kb.log_event, "EXECUTIVE_STOPPED", self.robot.name)
            context = Context(self.robot, self.bus, self.kb)
            relay = EventRelay(context)
            manager = LifecycleManager(
                [relay, *self._planning(context, relay, stack)],
                progress=self.progress,
                on_failure=self.on_failure,
            )
            stack.callback(manager.close)
            manager.configure()  # the bus API answers from here on
            if self.on_open is not None:
                self.on_open()
            if TASKS not in self.without:
                self.progress("loading the launcher")
                self.launcher = stack.enter_context(
                    launcher(context, self.settings, credentials, lock.run_id)
                )
            if self.robot.ros2 is not None:  # Cyclone DDS loads only for a ROS 2 robot
                self.progress("joining the ROS 2 domain")
                self.ros2 = stack.enter_context(ros2_link(self.robot))
            self.progress("loading the services")
            manager.add(self.services(context), before=self.high_level)
            manager.configure()
            manager.activate()
            self.bus.declare_alive(EXECUTIVE_ALIVE)
            self._stack = stack.pop_all()
        return self

    def _planning(
        self, context: Context, relay: EventRelay, stack: contextlib.ExitStack[Any]
    ) -> list[Service]:
        """The high level (unless another process runs it): built and configured before
        the other services are loaded, so that its API answers and its planner warms up
        at once; it runs its steps on the task executor of this process (built after it)
        or of the tasks process (over the bus)."""
        if PLANNING in self.without:
            return []
        sources = self._topic_sources
        if TASKS in self.without:
            steps = bus_tasks(self.robot, self.bus, service_alive(TASKS))
            stack.callback(steps.close)
            status = remote_status(self.bus)
            self.high_level = planning_group(context, relay, lambda: steps, status, sources)
        else:
            status = self._local_status()
            self.high_level = planning_group(context, relay, self._local_steps, status, sources)
        return [self.high_level]

    def services(self, context: Context) -> list[Service]:
        """The services of the executive after its high level, in the order they configure
        and activate: the recording first, so that it sees all; monitoring before the
        task executor, so that it watches every component it starts. The high level
        activates after them all, so that it plans once everything else runs."""
        services: list[Service] = [
            *recording_group(
                context, self.record, self.record_max_size, self.ros2, self.record_flush
            ),
            *(
                monitoring_group(context, self._topic_sources())
                if MONITORING not in self.without
                else []
            ),
            *ros2_group(context, self.ros2),
        ]
        if self.launcher is not None:
            # the steps of a high level in another process: the planning process's, or a
            # fleet's (dura fleet run), beside this process's own high level
            self._tasks_group = tasks_group(context, self.launcher, self.settings, steps=True)
            self.tasks = self._tasks_group.executor
            services += self._tasks_group.services
        return services

    def _topic_sources(self) -> list[TopicSource]:
        """The topics not on the bus: ROS 2's, for a ROS 2 robot."""
        return [self.ros2.topics] if self.ros2 is not None else []

    def _local_steps(self) -> TaskRunner:
        """This process's task executor, as the runner of the high level's steps."""
        if self._tasks_group is None:
            raise DuraError("the task executor has not started")
        return self._tasks_group.runner()

    def _local_status(self) -> StatusSections:
        """The sections of ``status`` this process's task executor and launcher answer
        (they say so while they are loading)."""

        def section(name: str) -> Any:
            if self._tasks_group is None:
                raise DuraError("the task executor is starting")
            return self._tasks_group.status()[name]()

        return {name: functools.partial(section, name) for name in ("tasks", "components")}

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
        self.settings = TaskSettings(
            log_dir or self.folder / ".dura" / "logs", resource_rate, grace, linger,
            sequential_starts,
        )  # fmt: skip

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
            context = Context(self.robot, bus, kb)

            def failed(reason: str) -> None:
                self._say(f"stops: {reason}")
                stop.set()

            services = self._services(context, stack, "" if lock is None else lock.run_id)
            manager = LifecycleManager(services, on_failure=failed)
            stack.callback(manager.close)
            manager.configure()
            manager.activate()
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
        self, context: Context, stack: contextlib.ExitStack[Any], run_id: str
    ) -> list[Service]:
        """The group's services, after the event relay: what these services log (rule
        firings, task ends, ...) is on the bus, as the executive's own events are (for
        the high level, dura events --follow, the dashboard, the recorder). ``run_id``:
        the tasks group's run lock's, which marks the processes it starts."""
        robot, bus = self.robot, context.bus
        relay = EventRelay(context)
        sources: list[TopicSource] = []
        reads_topics = self.group == MONITORING or (self.group == PLANNING and robot.sensing)
        if robot.ros2 is not None and reads_topics:  # observers, sensing rules
            sources.append(stack.enter_context(ros2_link(robot, self.group)).topics)
        if self.group == MONITORING:
            return [relay, *monitoring_group(context, sources)]
        if self.group == PLANNING:
            steps = bus_tasks(robot, bus, EXECUTIVE_ALIVE)
            stack.callback(steps.close)
            high_level = planning_group(
                context, relay, lambda: steps, remote_status(bus), lambda: sources
            )
            return [relay, high_level]
        # each component's login: the tasks process runs in the executive's folder
        credentials = security.read_credentials(security.credentials_file(self.folder, robot.name))
        running = stack.enter_context(launcher(context, self.settings, credentials, run_id))
        return [relay, *tasks_group(context, running, self.settings, steps=True).services]
