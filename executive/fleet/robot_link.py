"""One robot as its fleet reaches it: a bus session to the robot's executive, logged in
as the ``fleet`` role, and the robot's task executor as a runner of plan steps
(:class:`~executive.planning.bus_tasks.BusTasks`).

The link connects in the background and keeps trying while the executive is not
there (its login file is read at each try: the executive writes it on its first run).
Once connected it watches the executive's liveliness token: the link tells who asks
whether the robot is there, before the steps running there fail when it vanishes; the
session stays open, and the robot is there again when its executive comes back. It
also hands on the robot's events (``on_event``: its facts follow them,
:mod:`.robot_facts`).
"""

from __future__ import annotations

import threading
from collections.abc import Callable
from pathlib import Path

from executive.bus import security
from executive.bus.keys import EVENTS, EXECUTIVE_ALIVE
from executive.bus.message import Message
from executive.bus.session import Bus, connect_when_there
from executive.planning.bus_tasks import BusTasks
from knowledge.description import RobotDescription


class RobotLink:
    """The fleet's link to one robot.

    Args:
        robot: the robot's description.
        endpoint: where its executive listens.
        login_file: the fleet's login on its bus.
        fleet: the fleet's name (the session's name on the robot's bus).
        on_alive: told ``(robot, there)`` whenever its executive comes or goes.
        say: told one line at each change, for the operator.
        on_event: told ``(kind, subject)`` of each event the robot logs.
        lease: seconds of silence after which the link to the robot counts as lost (its
            executive out of reach: a robot whose network broke is noticed then).
    """

    def __init__(
        self,
        robot: RobotDescription,
        endpoint: str,
        login_file: Path,
        fleet: str,
        *,
        on_alive: Callable[[str, bool], None],
        say: Callable[[str], None] = lambda line: None,
        on_event: Callable[[str, str], None] | None = None,
        lease: float | None = None,
    ) -> None:
        self.robot = robot
        self.name = robot.name
        self.endpoint = endpoint
        self.login_file = login_file
        self.fleet = fleet
        self.on_alive = on_alive
        self.say = say
        self.on_event = on_event
        self.lease = lease
        self.runner: BusTasks | None = None  # once connected
        self.bus: Bus | None = None
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._connect, name=f"link {self.name}", daemon=True)

    def start(self) -> None:
        self._thread.start()

    def close(self) -> None:
        self._stop.set()
        self._thread.join()
        if self.runner is not None:
            self.runner.close()
        if self.bus is not None:
            self.bus.close()

    def _connect(self) -> None:
        def connect() -> Bus:
            login = security.read_credentials(self.login_file).login(security.FLEET)
            return Bus(self.name, name=f"fleet.{self.fleet}", endpoint=self.endpoint,
                       login=login, lease=self.lease)  # fmt: skip

        bus = connect_when_there(connect, self.endpoint, self._stop, self._waiting)
        if bus is None:
            return
        interruptible = {
            action: self.robot.behaviors[task.behavior].interruptible
            for action, task in self.robot.tasks.items()
            if task.behavior in self.robot.behaviors
        }
        self.bus = bus
        if self.on_event is not None:
            bus.subscribe(EVENTS, self._event)
        self.runner = BusTasks(
            bus, interruptible, EXECUTIVE_ALIVE, on_server=self._alive, fleet=self.fleet
        )

    def _event(self, message: Message) -> None:
        payload = message.payload
        if self.on_event is not None and isinstance(payload, dict):
            kind, subject = payload.get("kind"), payload.get("subject")
            if isinstance(kind, str) and isinstance(subject, str):
                self.on_event(kind, subject)

    def _waiting(self, line: str) -> None:
        self.say(f"robot '{self.name}': {line}")

    def _alive(self, there: bool) -> None:
        if not self._stop.is_set():
            self.on_alive(self.name, there)
