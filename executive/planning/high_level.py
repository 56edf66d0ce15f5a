"""The high level of the executive (thesis 5.1.2) as one service: a small shell over parts
with one job each.

- :mod:`.warm_up` — in the background, the planner worker loads the domain, the robot is
  checked against it, a new robot's world is loaded, the integrity rules are read;
- :mod:`.deliberation` — once warm and active: the goal planner, the plan executor, the
  integrity goals (:mod:`.integrity_loop`) and the sensing rules;
- :mod:`.goal_api` and :mod:`.world_api` — the verbs of :mod:`executive.bus.api.planning`;
- the process's :class:`~executive.bus.event_relay.EventRelay` hands it the events of
  every process (a task executor or repair rules that run apart included).

Configured (:meth:`~executive.bus.service.Service.configure`), it takes back what a
killed executive's unfinished steps did (:mod:`executive.planning.recovery`), answers on
the bus and warms its planner up; ``status``, ``goal/list``, ``events`` and the other
readers answer at once, and a request that needs the domain (a goal, a fact, an object)
waits for the high level to plan. Activated, it plans as soon as the planner is warm
(ACTIVATING until then), beginning with the goals still open in the knowledge base: an
executive restarted after a crash carries on with them. A domain that does not fit the
robot puts it in ERROR with the one-line reason (the process's
:class:`~executive.bus.lifecycle_manager.LifecycleManager` reports it).

What carries out the plan steps (the task executor of this process, or another's over
the bus) and where the robot's sensing rules (:mod:`executive.planning.sensing`) read
their topics (the bus, or ROS 2) are ports it is given, used once it plans: so the high
level is built, and answers, before the rest of its process is loaded.
"""

from __future__ import annotations

import contextlib
import logging
import threading
from collections.abc import Callable, Collection, Mapping
from typing import Any

from executive.bus.clock import Clock, system_clock
from executive.bus.event_relay import EventRelay
from executive.bus.keys import DIAGNOSES
from executive.bus.message import Message
from executive.bus.reports import DiagnosisInfo
from executive.bus.service import Context, Service, ServiceState
from executive.planning.deliberation import Deliberation
from executive.planning.goal_api import GoalApi
from executive.planning.plan_executor import ExecutionLimits, TaskRunner
from executive.planning.portfolio import planner_for
from executive.planning.recovery import recover
from executive.planning.sensing import Subscribe
from executive.planning.warm_up import Warm, WarmUp, WarmUpState
from executive.planning.world_api import RefuseObject, WorldApi
from knowledge.errors import DuraError

log = logging.getLogger("dura.high_level")
WARM_UP_WAIT = 25.0  # seconds a request waits for the planner at start (callers wait 30)


class HighLevel(Service):
    """Goal planner, plan executor and integrity goals, served on the bus.

    Args:
        context: the robot, bus and knowledge base.
        runner: what carries out plan steps (the task executor's adapter), asked for once
            when the high level begins planning (raises
            :class:`~knowledge.errors.DuraError` if there is none).
        events: the process's event relay (the high level follows every event).
        status: the sections other services add to ``status`` (``tasks`` from the task
            executor, ``components`` from the launcher), by name.
        limits: when a running step times out.
        clock: robot time (default: this process's, from ``DURA_TIME_SCALE``).
        subscribe: how sensing rules subscribe to a topic key (default: on the bus).
        actions: the actions whose steps ``runner`` carries out (default: the robot's
            tasks).
        unavailable: the objects that cannot act now (a fleet's lost robots).
        refuse_object: why a new object may not be added to the world (a fleet's: an
            object of its robot type that is no robot of it).
    """

    name = "high-level"
    activates_later = True  # active once the planner is warm

    def __init__(
        self,
        context: Context,
        runner: Callable[[], TaskRunner],
        *,
        events: EventRelay,
        status: Mapping[str, Callable[[], Any]] | None = None,
        limits: ExecutionLimits | None = None,
        clock: Clock | None = None,
        subscribe: Subscribe | None = None,
        actions: Collection[str] | None = None,
        unavailable: Callable[[], Collection[str]] | None = None,
        refuse_object: RefuseObject | None = None,
    ) -> None:
        super().__init__(context)
        robot = context.robot
        self.runner = runner
        self.limits = limits
        self.clock = clock or system_clock()
        self.subscribe: Subscribe = subscribe or context.bus.subscribe
        self.actions = actions
        self.unavailable = unavailable
        self.planner = planner_for(robot.planner)
        self.warm_up = WarmUp(robot, context.kb, self.planner, on_failure=self.fail)
        self.goal_api = GoalApi(
            context,
            planning=lambda: self.deliberation,
            current=lambda: self._deliberation,
            diagnoses=lambda: self._diagnoses,
            status=status or {},
        )
        self.world_api = WorldApi(context, self.warm_up, lambda: self.deliberation, refuse_object)
        self._deliberation: Deliberation | None = None  # while it plans
        self._diagnoses: dict[str, Any] = {}  # the latest diagnosis result
        self._diagnoses_lock = threading.Lock()  # the diagnoses, and the deliberation's birth
        self._activation = threading.Lock()  # one (de)activation at a time
        self._declared: list[Any] = []
        events.follow(self._followed)

    @property
    def deliberation(self) -> Deliberation:
        """The high level at work, once it plans (waits up to :data:`WARM_UP_WAIT`).

        Raises:
            DuraError: it does not plan: it failed, or its planner is not warm in time.
        """
        if self.wait_for(ServiceState.ACTIVE, WARM_UP_WAIT):
            deliberation = self._deliberation
            if deliberation is not None:
                return deliberation
        if self.state is ServiceState.ERROR:
            raise DuraError(f"the executive cannot plan: {self.reason}")
        if self.warm_up.state is WarmUpState.LOADING:
            raise DuraError(
                "the executive is still starting: its planner has not loaded the domain "
                f"within {WARM_UP_WAIT:g} s; try again"
            )
        raise DuraError(f"the executive does not plan now (its high level is {self.state.value})")

    # --- the lifecycle -------------------------------------------------------------------

    def on_configure(self) -> None:
        recover(self.context.kb)  # before anything executes: the knowledge base only, fast
        self._declared = [
            self.context.bus.subscribe(DIAGNOSES, self._on_diagnoses),
            *self.goal_api.serve(),
            *self.world_api.serve(),
        ]
        self.warm_up.start()

    def on_activate(self) -> None:
        self.warm_up.when_warm(self._plan)

    def on_deactivate(self) -> None:
        with self._activation:
            deliberation, self._deliberation = self._deliberation, None
        if deliberation is not None:
            deliberation.stop()

    def on_shutdown(self) -> None:
        self.warm_up.stop()
        for entity in self._declared:
            with contextlib.suppress(Exception):
                entity.undeclare()
        self._declared = []
        self.planner.close()

    def _plan(self, warm: Warm) -> None:
        """Begin planning (on the warm-up's thread, or the activating one if warm)."""
        with self._activation:
            if self.state is not ServiceState.ACTIVATING:
                return  # deactivated meanwhile
            try:
                runner = self.runner()
                with self._diagnoses_lock:  # the diagnoses that came meanwhile, then each
                    deliberation = self._deliberation = Deliberation(
                        self.context,
                        warm,
                        self.planner,
                        runner,
                        limits=self.limits,
                        clock=self.clock,
                        subscribe=self.subscribe,
                        diagnoses=self._diagnoses,
                        actions=self.actions,
                        unavailable=self.unavailable,
                    )
                # started outside the diagnoses' lock: starting subscribes on the bus,
                # whose callback threads may be waiting for the lock (a diagnosis)
                deliberation.start()
            except Exception as e:  # a bug: say so, rather than leave goals waiting
                log.exception("the high level could not begin planning")
                self.fail(str(e) if isinstance(e, DuraError) else f"{type(e).__name__}: {e}")
                return
            self._activated()

    def replan(self, reason: str) -> None:
        """Plan again now if it plans (a fleet's robot was lost or is back)."""
        deliberation = self._deliberation
        if deliberation is not None:
            deliberation.replan(reason)

    # --- what it hears -------------------------------------------------------------------

    def _followed(self, kind: str, subject: str) -> None:
        """An event of this process or another (until it plans, the goal planner's first
        round sees it all)."""
        deliberation = self._deliberation
        if deliberation is not None:
            deliberation.followed(kind, subject)

    def _on_diagnoses(self, message: Message) -> None:
        try:
            payload = DiagnosisInfo.from_payload(message.payload).to_payload()
        except (KeyError, ValueError, TypeError) as e:
            log.warning("ignored a malformed diagnosis on %s: %s", message.key, e)
            return
        with self._diagnoses_lock:
            self._diagnoses = payload
            if self._deliberation is not None:
                self._deliberation.diagnosed(payload)
