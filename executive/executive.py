"""The executive process: its bus (listening), knowledge base, launcher and services
(monitoring, diagnosis, repair rules, task executor, high level).

The bus API answers first: as soon as the bus listens and the knowledge base is open,
the high level recovers from a crash, serves its verbs (``status`` among them) and
warms its planner up in the background; only then are the other services' modules
imported and the services started, in order (and stopped in reverse). The high level
begins planning once all of them run. The launcher stops every component when the
executive closes. While it runs, the executive holds the liveliness token
``alive/executive``: components end themselves when it vanishes.
"""

from __future__ import annotations

import contextlib
import os
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING, Any

from executive.bus import security
from executive.bus.clock import system_clock
from executive.bus.keys import EXECUTIVE_ALIVE
from executive.bus.service import Context, Service
from executive.bus.session import Bus
from executive.planning.high_level import HighLevel
from executive.runtime.run_lock import RunLock, end_leftovers
from knowledge.description import RobotDescription
from knowledge.errors import DuraError
from knowledge.knowledge_base import KnowledgeBase

if TYPE_CHECKING:
    from executive.ros2.link import Ros2Link
    from executive.runtime.launcher import Launcher
    from executive.tasks.executor import TaskExecutor
    from executive.tasks.plan_tasks import PlanTasks


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
    ) -> None:
        self.robot = robot
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
            credentials = security.ensure_credentials(self.credentials_path, robot.name, components)
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
                    access=security.access_control(robot.name, components),
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
            self.high_level = HighLevel(
                context,
                self._plan_tasks,
                status={"tasks": self._tasks, "components": self._components},
                on_failure=self.on_failure,
            )
            self.high_level.open()  # the API answers from here on
            stack.callback(self.high_level.stop)  # if a later start fails
            if self.on_open is not None:
                self.on_open()
            self.progress("loading the launcher")
            from executive.runtime.launcher import Launcher

            self.launcher = stack.enter_context(
                Launcher(
                    self.robot,
                    self.bus,
                    self.kb,
                    log_dir=self.log_dir,
                    grace=self.grace,
                    credentials=credentials,
                    run_id=lock.run_id,
                )
            )
            self.ros2: Ros2Link | None = None
            if self.robot.ros2 is not None:  # Cyclone DDS loads only for a ROS 2 robot
                self.progress("joining the ROS 2 domain")
                from executive.ros2.link import Ros2Link

                nodes = {c.ros2.node: name for name, c in self.robot.components.items()
                         if c.ros2 is not None and c.ros2.node is not None}  # fmt: skip
                self.ros2 = stack.enter_context(Ros2Link(self.robot.ros2, nodes=nodes))
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
        from executive.runtime.component_api import ComponentApi
        from executive.tasks.executor import TaskExecutor
        from monitoring.diagnosis.service import DiagnosisService
        from monitoring.observer_manager import ObserverManager
        from monitoring.repair.service import RuleService
        from monitoring.resource_monitor import ResourceMonitor

        launcher = self.launcher
        if launcher is None:
            raise DuraError("the launcher must run before the services")
        self.tasks = TaskExecutor(
            context, launcher, linger=self.linger, sequential=self.sequential_starts
        )
        ros2 = self.ros2
        extra: list[Service] = []
        last: list[Service] = []
        if ros2 is not None:
            from executive.ros2.goals import Ros2Goals
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
            ComponentApi(context, launcher, by_hand=self.tasks),
            ResourceMonitor(context, rate=self.resource_rate),
            ObserverManager(context, sources=[ros2.topics] if ros2 is not None else []),
            DiagnosisService(context, learn=True),
            RuleService(context),
            *extra,
            self.tasks,
            self.high_level,
            *last,
        ]

    def _plan_tasks(self) -> PlanTasks:
        """The task executor as the high level's runner of plan steps (once it runs)."""
        from executive.tasks.plan_tasks import PlanTasks

        if self.tasks is None:
            raise DuraError("the task executor has not started")
        return PlanTasks(self.tasks, self.robot)

    def _tasks(self) -> list[dict[str, Any]]:
        if self.tasks is None:
            raise DuraError("the task executor is starting")
        return self.tasks.tasks()

    def _components(self) -> list[dict[str, Any]]:
        if self.launcher is None:
            raise DuraError("the launcher is starting")
        from executive.runtime.component_api import listed

        return [listed(self.launcher, s) for s in self.launcher.states()]

    def __exit__(self, *exc: object) -> None:
        self._stack.close()
