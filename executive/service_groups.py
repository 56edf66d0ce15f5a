"""One builder per group of services, used alike by the executive process and by a
group's process of its own (:mod:`executive.executive`).

- :func:`monitoring_group` — observers, diagnosis, repair rules;
- :func:`tasks_group` — the components' verbs and resource monitor, the task executor,
  and (for a high level elsewhere) the plan steps it asks for over the bus;
- :func:`planning_group` — the high level;
- what only the executive runs: :func:`recording_group` (``dura run --record``) and
  :func:`ros2_group` (dura's state, the diagnosis model's ROS 2 nodes, goals from ROS 2).

Each builder returns its services in the order they configure and activate; the
composition root puts the groups in order (recording first, so that it sees all; then
monitoring, so that it watches every component the task executor starts; the high
level last, so that it plans once everything else runs) and hands the list to a
:class:`~executive.bus.lifecycle_manager.LifecycleManager`. Every process also runs an
:class:`~executive.bus.event_relay.EventRelay`, first. Modules load only for the groups
a process runs.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

from executive.bus import security
from executive.bus.event_relay import EventRelay
from executive.bus.service import Context, Service, ServiceState
from executive.bus.session import Bus, Handler
from knowledge.description import RobotDescription
from knowledge.errors import DuraError

if TYPE_CHECKING:
    from executive.bus.reports import ComponentEntry, ExecutorTask
    from executive.bus.topic_source import Subscription, TopicSource
    from executive.planning.bus_tasks import BusTasks
    from executive.planning.high_level import HighLevel
    from executive.planning.task_runner import TaskRunner
    from executive.ros2.link import Ros2Link
    from executive.runtime.launcher import Launcher
    from executive.tasks.executor import TaskExecutor

StatusSections = dict[str, Callable[[], Any]]
"""The sections the task executor adds to the high level's ``status``, by name."""


@dataclass(frozen=True)
class TaskSettings:
    """How the tasks group runs the components (``dura run``'s options)."""

    log_dir: Path
    resource_rate: float = 1.0
    grace: float = 3.0
    linger: float = 0.0
    sequential_starts: bool = False


def ros2_link(robot: RobotDescription, group: str | None = None) -> Ros2Link:
    """The robot's ROS 2 link (the robot has a ``ros2:`` section): the executive's, or
    that of a group of services in a process of its own (node ``dura_monitoring``).
    Cyclone DDS loads only here, for a ROS 2 robot."""
    from executive.ros2.link import Ros2Link

    return Ros2Link.of(robot, group)


def launcher(
    context: Context, settings: TaskSettings, credentials: security.Credentials, run_id: str
) -> Launcher:
    """The launcher of the components placed on this computer (and of the host agents')."""
    from executive.runtime.launcher import Launcher

    return Launcher(
        context.robot,
        context.bus,
        context.kb,
        log_dir=settings.log_dir,
        grace=settings.grace,
        credentials=credentials,
        run_id=run_id,
    )


def remote_status(bus: Bus) -> StatusSections:
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


# --- the groups ------------------------------------------------------------------------


def recording_group(
    context: Context,
    path: Path | None,
    max_size: int | None,
    ros2: Ros2Link | None = None,
    flush_every: float | None = None,
) -> list[Service]:
    """The executive's own recording, if it records (first: it sees every other
    service's traffic), with the robot's ROS 2 topics in their ROS 2 types."""
    if path is None:
        return []
    from executive.bags.recording import DEFAULT_FLUSH_EVERY, DEFAULT_MAX_SIZE, Recording

    size, flush = max_size or DEFAULT_MAX_SIZE, flush_every or DEFAULT_FLUSH_EVERY
    topics = None if ros2 is None else ros2.topics
    return [Recording(context, path, max_size=size, flush_every=flush, ros2=topics)]


def ros2_group(context: Context, link: Ros2Link | None) -> list[Service]:
    """dura's state on ROS 2, the diagnosis model's ROS 2 nodes, goals from ROS 2 (for a
    robot with a ``ros2:`` section)."""
    if link is None:
        return []
    from executive.ros2.goal_topic import Ros2Goals
    from executive.ros2.graph_model import Ros2GraphModel
    from executive.ros2.state import Ros2StatePublisher

    return [
        Ros2StatePublisher(context, link.spec, link=link),
        Ros2GraphModel(context, link.discovery),
        Ros2Goals(context, link),
    ]


def monitoring_group(context: Context, sources: Sequence[TopicSource] = ()) -> list[Service]:
    """The observers, the diagnosis engine and the repair rules."""
    from monitoring.diagnosis.diagnosis_service import DiagnosisService
    from monitoring.observer_manager import ObserverManager
    from monitoring.repair.rule_service import RuleService

    return [
        ObserverManager(context, sources=list(sources)),
        DiagnosisService(context, learn=True),
        RuleService(context),
    ]


@dataclass(frozen=True)
class TasksGroup:
    """The tasks group's services, and what the high level of the same process needs of
    them."""

    services: list[Service]
    executor: TaskExecutor
    launcher: Launcher

    def runner(self) -> TaskRunner:
        """The task executor as the high level's runner of plan steps."""
        from executive.tasks.plan_tasks import PlanTasks

        return PlanTasks(self.executor, self.executor.robot)

    def status(self) -> StatusSections:
        """The sections of ``status`` the task executor and the launcher answer."""
        return {"tasks": self._tasks, "components": self._components}

    def _tasks(self) -> list[ExecutorTask]:
        if self.executor.state is not ServiceState.ACTIVE:
            raise DuraError("the task executor is starting")
        return self.executor.tasks()

    def _components(self) -> list[ComponentEntry]:
        from executive.runtime.component_api import listed

        return [listed(self.launcher, s) for s in self.launcher.states()]


def tasks_group(
    context: Context, launcher: Launcher, settings: TaskSettings, *, steps: bool
) -> TasksGroup:
    """The verbs of the components ``launcher`` launches and their resource monitor, the
    task executor, and (``steps``: for a high level in another process) the plan steps
    asked for over the bus."""
    from executive.runtime.component_api import ComponentApi
    from executive.tasks.executor import TaskExecutor
    from monitoring.resource_monitor import ResourceMonitor

    tasks = TaskExecutor(
        context, launcher, linger=settings.linger, sequential=settings.sequential_starts
    )
    services: list[Service] = [
        ComponentApi(context, launcher, by_hand=tasks),
        ResourceMonitor(  # host agents measure the components they run themselves
            context, rate=settings.resource_rate, components=context.robot.placed_on(None)
        ),
        tasks,
    ]
    if steps:
        from executive.tasks.step_service import StepService

        services.append(StepService(context, tasks))
    return TasksGroup(services, tasks, launcher)


def planning_group(
    context: Context,
    events: EventRelay,
    runner: Callable[[], TaskRunner],
    status: StatusSections,
    sources: Callable[[], Sequence[TopicSource]] = tuple,
) -> HighLevel:
    """The high level: goals, planner, plan executor and their verbs (``status`` among
    them). ``runner`` gives what runs its steps, and ``sources`` the topics not on the bus
    (ROS 2) that its sensing rules may read, once it plans."""
    from executive.planning.high_level import HighLevel

    bus = context.bus

    def subscribe(key: str, handler: Handler) -> Subscription:
        """A sensing rule's topic: on the source that serves it, else on the bus."""
        source = next((s for s in sources() if s.serves(key)), None)
        found: Subscription = (
            bus.subscribe(key, handler) if source is None else source.subscribe(key, handler)
        )
        return found

    return HighLevel(context, runner, events=events, status=status, subscribe=subscribe)
