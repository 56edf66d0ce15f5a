"""The diagnosis model follows the running components: the task executor tells the
diagnosis engine (``DIAGNOSIS_MODEL_CHANGE``) when a component it started is ready
(ADD) and when it stops (REMOVE), with the topics it subscribes and publishes.

A refused change is a warning with the reason (the component's next start tries
again). A change nobody answered (the engine runs in a process of its own, ``dura run
--only monitoring``, that is not there yet, restarts or is slow) is a warning too, and
is not lost: the model is brought in line later, from what the engine holds (GET) and
what runs, after a pause that doubles while nobody answers, and at once whenever a
monitoring process joins (its liveliness token appears), whose new engine knows nothing
yet.
"""

from __future__ import annotations

import contextlib
import logging
from collections.abc import Callable

from executive.bus.api.monitoring import DIAGNOSIS_MODEL_CHANGE, ModelChange
from executive.bus.keys import service_alive
from executive.bus.session import Bus
from executive.bus.timers import Timer, later
from knowledge.description import RobotDescription
from knowledge.errors import DuraError

log = logging.getLogger("dura.task_executor")

MODEL_TIMEOUT = 1.0  # seconds to wait for the diagnosis engine's answer
RETRY = 1.0  # seconds before the first attempt to bring the model in line again
RETRY_MAX = 30.0  # the longest pause between two attempts
ADD, REMOVE, GET = "ADD", "REMOVE", "GET"
MONITORING_ALIVE = service_alive("monitoring")  # a monitoring process of its own runs

Post = Callable[[Callable[[], None]], None]


class DiagnosisModelSync:
    """Keeps the diagnosis engine's nodes in line with the components that run.

    Args:
        bus: where the diagnosis engine answers.
        robot: the components' topics.
        post: runs a job on the owner's thread (every method runs there); without it,
            a change nobody answered waits for the component's next change.
    """

    def __init__(self, bus: Bus, robot: RobotDescription, post: Post | None = None) -> None:
        self.bus = bus
        self.robot = robot
        self._post = post
        self._wanted: set[str] = set()  # the components that run: their nodes belong there
        self._modelled: set[str] = set()  # the nodes the engine holds, as far as we know
        self._refused: set[str] = set()  # refused until the component's next start
        self._pause = RETRY
        self._timer: Timer | None = None
        self._watch = None if post is None else bus.watch_alive(MONITORING_ALIVE, self._joined)

    def add(self, name: str) -> None:
        """A component runs: add its node."""
        self._wanted.add(name)
        self._refused.discard(name)
        self._sync(name)

    def remove(self, name: str) -> None:
        """A component stops: remove its node."""
        self._wanted.discard(name)
        self._sync(name)

    def resync(self) -> None:
        """Bring the model in line with what runs, from what the engine holds now."""
        self._timer = None
        try:
            reply = DIAGNOSIS_MODEL_CHANGE.call(self.bus, ModelChange(GET), timeout=MODEL_TIMEOUT)
        except DuraError:
            self._later()
            return
        nodes = (reply.model or {}).get("nodes", [])
        self._modelled = {n["name"] for n in nodes} & set(self.robot.components)
        self._pause = RETRY
        for name in sorted((self._wanted ^ self._modelled) - self._refused):
            if not self._sync(name):
                return

    def close(self) -> None:
        """Stop watching and retrying."""
        if self._timer is not None:
            self._timer.cancel()
            self._timer = None
        if self._watch is not None:
            with contextlib.suppress(Exception):
                self._watch.undeclare()
            self._watch = None

    def _sync(self, name: str) -> bool:
        """Ask for the change that ``name`` needs, if any; False if nobody answered."""
        wanted = name in self._wanted
        if wanted == (name in self._modelled):
            return True
        action = ADD if wanted else REMOVE
        component = self.robot.components[name]
        node = {"name": name, "sub_topic": list(component.subscribes),
                "pub_topic": list(component.publishes)}  # fmt: skip
        try:
            reply = DIAGNOSIS_MODEL_CHANGE.call(
                self.bus, ModelChange(action, nodes=[node]), timeout=MODEL_TIMEOUT
            )
        except DuraError as e:  # no answer, or an answer that is not a model reply
            log.warning("diagnosis model not updated (%s %s): %s", action, name, e)
            self._later()
            return False
        if not reply.ok:
            log.warning("diagnosis model refused %s %s: %s", action, name, reply.error)
            self._refused.add(name)
            return True
        if wanted:
            self._modelled.add(name)
        else:
            self._modelled.discard(name)
        return True

    def _later(self) -> None:
        """Try again after a pause (doubled each time nobody answers)."""
        post = self._post
        if post is None or self._timer is not None:
            return
        self._timer = later(self._pause, lambda: post(self.resync))
        self._pause = min(RETRY_MAX, 2 * self._pause)

    def _joined(self, _: str, alive: bool) -> None:
        """A monitoring process joined: its engine's model starts empty (bus thread)."""
        if alive and self._post is not None:
            self._pause = RETRY
            self._post(self.resync)
