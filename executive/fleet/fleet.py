"""The fleet's process (``dura fleet run``): its own bus and knowledge base, a link to
each robot, and the executive's high level on the fleet's domain.

The fleet listens on its own bus (``dura/<fleet>/``) as an executive does, so that the
operators' commands (``dura goal add``, ``status``, ``plan show``, the dashboard) reach
its high level there; its goals, plans, world and events are in its own knowledge base.
Each plan step goes to the robot it names (:mod:`.fleet_tasks`), over that robot's bus
(:mod:`.robot_link`). When a robot comes or goes, the event is logged (``ROBOT_JOINED``,
``ROBOT_LOST``) and the fleet plans again: without a lost robot, with one that is back.
Once its API answers, the fleet waits a little (:data:`JOIN_WAIT`) for every robot, so
that its first plan shares the work among all that are there.
"""

from __future__ import annotations

import contextlib
import logging
import os
import time
from collections.abc import Callable, Collection, Mapping, Sequence
from pathlib import Path

from executive.bus import security
from executive.bus.api.planning import (
    STATE_GET,
    STATE_SET,
    STATE_UNSET,
    FactChange,
    FleetRobot,
    StateQuery,
)
from executive.bus.event_relay import EventRelay
from executive.bus.keys import EXECUTIVE_ALIVE
from executive.bus.lifecycle_manager import LifecycleManager
from executive.bus.service import Context
from executive.bus.session import Bus
from executive.fleet.availability import Availability
from executive.fleet.description import FleetDescription
from executive.fleet.fleet_tasks import FleetTasks
from executive.fleet.robot_facts import FactMapping, RobotFacts
from executive.fleet.robot_link import RobotLink
from executive.planning.high_level import HighLevel
from knowledge.description import RobotDescription
from knowledge.domain import DomainInfo
from knowledge.errors import DuraError
from knowledge.knowledge_base import KnowledgeBase
from knowledge.records import Fact

log = logging.getLogger("dura.fleet")

JOIN_WAIT = 10.0  # seconds the fleet waits for its robots before it first plans


class Fleet:
    """Everything the fleet's process runs, opened and closed together.

    Args:
        fleet: the fleet.
        robots: each robot's description, by name (as :mod:`.validation` read them).
        actors: each acting action's robot parameter, by its position.
        outside: the objects of the robot type that are no robot of the fleet.
        mappings: the robots' own facts that reach the fleet's world.
        endpoint: where the fleet listens (default: its description's).
        kb_path: its knowledge base (default: ``./.dura/<fleet>.db``).
        folder: the working folder whose ``.dura/`` holds the fleet's bus credentials.
        join_wait: seconds to wait for the robots before the first plan.
        lease: seconds of silence after which a robot out of reach counts as lost.
        on_failure: called with the reason when the fleet cannot go on.
        on_open: called once the bus API answers (``dura fleet run`` writes its run file).
        say: told one line at each change of a robot, for the operator.
    """

    def __init__(
        self,
        fleet: FleetDescription,
        robots: Mapping[str, RobotDescription],
        actors: Mapping[str, int],
        *,
        outside: Collection[str] = (),
        mappings: Sequence[FactMapping] = (),
        endpoint: str | None = None,
        kb_path: Path | None = None,
        folder: Path | None = None,
        join_wait: float = JOIN_WAIT,
        lease: float | None = None,
        on_failure: Callable[[str], None] | None = None,
        on_open: Callable[[], None] | None = None,
        say: Callable[[str], None] = lambda line: None,
    ) -> None:
        self.fleet = fleet
        self.robot = fleet.as_robot()
        self.robots = dict(robots)
        self.actors = dict(actors)
        self.mappings = tuple(mappings)
        self.endpoint = endpoint or fleet.endpoint
        self.kb_path = kb_path or fleet.kb_path()
        self.folder = folder or Path.cwd()
        self.credentials_path = security.credentials_file(self.folder, fleet.name)
        self.join_wait = join_wait
        self.lease = lease
        self.on_failure = on_failure
        self.on_open = on_open
        self.say = say
        self.availability = Availability(
            {name: fleet.robots[name].pddl_object for name in self.robots},
            fleet.max_failures,
            self._changed,
            outside,
        )
        self.high_level: HighLevel | None = None
        self.links: dict[str, RobotLink] = {}
        self._facts_of: dict[str, RobotFacts] = {}  # each robot's facts, if any map
        self._stack = contextlib.ExitStack()
        self._kb: KnowledgeBase | None = None

    def __enter__(self) -> Fleet:
        with contextlib.ExitStack() as stack:
            credentials = security.ensure_credentials(self.credentials_path, self.fleet.name, [])
            users = self.credentials_path.with_suffix(".users")
            bus = stack.enter_context(
                Bus(
                    self.fleet.name,
                    name="executive",
                    endpoint=self.endpoint,
                    listen=True,
                    login=credentials.login(security.EXECUTIVE),
                    dictionary=security.dictionary(credentials, users),
                    access=security.access_control(self.fleet.name, []),
                )
            )
            kb = self._kb = stack.enter_context(KnowledgeBase(self.kb_path))
            kb.log_event(
                "EXECUTIVE_STARTED",
                self.fleet.name,
                {"endpoint": self.endpoint, "pid": os.getpid(), "robots": sorted(self.robots)},
            )
            stack.callback(kb.log_event, "EXECUTIVE_STOPPED", self.fleet.name)
            context = Context(self.robot, bus, kb)
            relay = EventRelay(context)
            for name, robot in self.robots.items():
                facts = self._facts(name, bus, kb)
                self.links[name] = RobotLink(
                    robot,
                    self.fleet.robots[name].endpoint or robot.endpoint,
                    self.fleet.login_file(self.fleet.robots[name]),
                    self.fleet.name,
                    on_alive=self._alive,
                    say=self.say,
                    on_event=facts.heard if facts is not None else None,
                    lease=self.lease,
                )
                if facts is not None:
                    self._facts_of[name] = facts
                    facts.start()
                    stack.callback(facts.stop)
            objects = {self.fleet.robots[name].pddl_object: name for name in self.robots}
            runner = FleetTasks(self.actors, objects, self.links, self.availability)
            self.high_level = HighLevel(
                context,
                lambda: runner,
                events=relay,
                status={"robots": self._robots},
                actions=frozenset(self.actors),
                unavailable=self.availability.unavailable_objects,
                refuse_object=self._refuse_object,
            )
            manager = LifecycleManager([relay, self.high_level], on_failure=self.on_failure)
            stack.callback(manager.close)
            manager.configure()  # the bus API answers from here on
            if self.on_open is not None:
                self.on_open()
            for link in self.links.values():
                link.start()
                stack.callback(link.close)
            self._wait_for_robots()
            manager.activate()
            bus.declare_alive(EXECUTIVE_ALIVE)
            self._stack = stack.pop_all()
        return self

    def __exit__(self, *exc: object) -> None:
        self._stack.close()

    def _facts(self, name: str, bus: Bus, kb: KnowledgeBase) -> RobotFacts | None:
        """What keeps the fleet's facts of a robot in step with its own (if any map)."""
        if not self.mappings:
            return None

        def ask(predicate: str) -> list[Fact]:
            link = self.links[name]
            if link.bus is None:
                return []
            return STATE_GET.call(link.bus, StateQuery(predicate)).facts

        def change(fact: str, unset: bool) -> None:
            verb = STATE_UNSET if unset else STATE_SET
            try:
                verb.call(bus, FactChange(fact, source=name))
            except DuraError as e:
                log.warning("robot %s: %s could not be %s: %s", name, fact,
                            "unset" if unset else "set", e)  # fmt: skip

        return RobotFacts(
            self.mappings,
            self.fleet.robots[name].pddl_object,
            ask=ask,
            fleet_facts=lambda predicate: [f for f in kb.facts() if f.name == predicate],
            change=change,
        )

    def _refuse_object(self, name: str, type_name: str, domain: DomainInfo) -> str | None:
        """Why an object may not be added at run time: one of the robot type that is no
        robot of the fleet would have no executive to carry out its steps."""
        ours = {robot.pddl_object for robot in self.fleet.robots.values()}
        if name in ours or not domain.is_a(type_name, self.fleet.robot_type):
            return None
        return (
            f"object '{name}' of type '{type_name}' is no robot of fleet '{self.fleet.name}' "
            f"(its robots: {', '.join(sorted(ours))}): a robot joins the fleet in "
            f"{self.fleet.path.name}, with its description, and the fleet runs again"
        )

    def _robots(self) -> list[FleetRobot]:
        """The fleet's robots and whether each can act (``status``)."""
        return [
            FleetRobot(name, why is None, why or "")
            for name, why in sorted(self.availability.snapshot().items())
        ]

    def _wait_for_robots(self) -> None:
        deadline = time.monotonic() + self.join_wait
        while time.monotonic() < deadline:
            if not self.availability.unavailable_objects():
                return
            time.sleep(0.05)

    def _alive(self, robot: str, there: bool) -> None:
        """A robot's executive came or went (on the link's bus thread)."""
        if there:
            self.availability.joined(robot)
            facts = self._facts_of.get(robot)
            if facts is not None:
                facts.joined()
        else:
            self.availability.lost(robot, "its executive vanished")

    def _changed(self, robot: str, available: bool, reason: str) -> None:
        kb = self._kb
        if kb is not None:
            kind = "ROBOT_JOINED" if available else "ROBOT_LOST"
            kb.log_event(kind, robot, {"reason": reason} if reason else {})
        self.say(f"robot '{robot}' " + ("joined" if available else f"is unavailable: {reason}"))
        if self.high_level is not None:  # only asks the goal planner: returns at once
            what = "joined" if available else "was lost"
            self.high_level.replan(f"robot {robot} {what}")
