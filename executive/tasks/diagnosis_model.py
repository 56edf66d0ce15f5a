"""The diagnosis model follows the running components: the task executor tells the
diagnosis engine (``DIAGNOSIS_MODEL_CHANGE``) when a component it started is ready
(ADD) and when it stops (REMOVE), with the topics it subscribes and publishes.

A refused change or one nobody answered leaves the diagnosis engine with a model that
is out of date, which makes its diagnoses wrong: it is a warning with the reason. The
next change of that component tries again.
"""

from __future__ import annotations

import logging

from executive.bus.api.monitoring import DIAGNOSIS_MODEL_CHANGE, ModelChange
from executive.bus.session import Bus
from knowledge.description import RobotDescription
from knowledge.errors import DuraError

log = logging.getLogger("dura.task_executor")

MODEL_TIMEOUT = 1.0  # seconds to wait for the diagnosis engine's answer
ADD, REMOVE = "ADD", "REMOVE"


class DiagnosisModelSync:
    """Keeps the diagnosis engine's nodes in line with the components that run.

    Args:
        bus: where the diagnosis engine answers.
        robot: the components' topics.
    """

    def __init__(self, bus: Bus, robot: RobotDescription) -> None:
        self.bus = bus
        self.robot = robot
        self._modelled: set[str] = set()  # the nodes the engine confirmed

    def add(self, name: str) -> None:
        """A component runs: add its node."""
        if name not in self._modelled and self._change(ADD, name):
            self._modelled.add(name)

    def remove(self, name: str) -> None:
        """A component stops: remove its node."""
        if name in self._modelled and self._change(REMOVE, name):
            self._modelled.discard(name)

    def _change(self, action: str, name: str) -> bool:
        """Ask the engine for the change; whether it made it."""
        component = self.robot.components[name]
        node = {"name": name, "sub_topic": list(component.subscribes),
                "pub_topic": list(component.publishes)}  # fmt: skip
        try:
            reply = DIAGNOSIS_MODEL_CHANGE.call(
                self.bus, ModelChange(action, nodes=[node]), timeout=MODEL_TIMEOUT
            )
        except DuraError as e:  # no answer, or an answer that is not a model reply
            log.warning("diagnosis model not updated (%s %s): %s", action, name, e)
            return False
        if not reply.ok:
            log.warning("diagnosis model refused %s %s: %s", action, name, reply.error)
        return reply.ok
