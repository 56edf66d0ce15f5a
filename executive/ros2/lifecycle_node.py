"""A managed (lifecycle) ROS 2 node, driven through its lifecycle services.

A managed node ``/navigator`` serves ``/navigator/get_state``
(``lifecycle_msgs/srv/GetState``) and ``/navigator/change_state``
(``lifecycle_msgs/srv/ChangeState``, a transition by id; the answer says whether it
succeeded), and publishes each transition it makes on ``/navigator/transition_event``
(``lifecycle_msgs/msg/TransitionEvent``). Its primary states are unconfigured,
inactive, active and finalized; the transitions between them are configure, cleanup,
activate, deactivate and shutdown (one id per state it starts from).

dura's lifecycle commands map onto them (:data:`DURA_TRANSITIONS`): configure is
configure, start and resume are activate, pause is deactivate, stop is deactivate (if
active) then cleanup.
"""

from __future__ import annotations

import logging
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from executive.ros2.cdr import CdrError
from executive.ros2.discovery import Discovery
from executive.ros2.names import dds_topic
from executive.ros2.participant import Participant, Reader
from executive.ros2.qos import dds_qos
from executive.ros2.service_client import ServiceClient
from executive.ros2.types import TypeLibrary
from knowledge.ros2_spec import PROFILES

log = logging.getLogger("dura.ros2")

STATES = {0: "unknown", 1: "unconfigured", 2: "inactive", 3: "active", 4: "finalized",
          10: "configuring", 11: "cleaningup", 12: "shuttingdown", 13: "activating",
          14: "deactivating", 15: "errorprocessing"}  # fmt: skip
TRANSITIONS = {"configure": 1, "cleanup": 2, "activate": 3, "deactivate": 4,
               "unconfigured_shutdown": 5, "inactive_shutdown": 6, "active_shutdown": 7}  # fmt: skip
# What each of dura's lifecycle commands asks of a managed node, from the state it
# is in (states from which nothing is to be done are absent).
DURA_TRANSITIONS: dict[str, dict[str, tuple[str, ...]]] = {
    "configure": {"unconfigured": ("configure",)},
    "start": {"inactive": ("activate",), "unconfigured": ("configure", "activate")},
    "pause": {"active": ("deactivate",)},
    "resume": {"inactive": ("activate",)},
    "stop": {"active": ("deactivate", "cleanup"), "inactive": ("cleanup",)},
}
TransitionListener = Callable[[str, str, str], None]  # (transition, from state, to state)


@dataclass(frozen=True)
class TransitionOutcome:
    """What a transition did: whether the node made it, and the state it is in after."""

    transition: str
    success: bool
    state: str


class LifecycleClient:
    """Drives one managed node through its lifecycle.

    Args:
        participant: the DDS participant to call from.
        library: the message types (lifecycle_msgs).
        node: the node's fully qualified name, e.g. ``/navigator``.
        discovery: when given, the client's endpoints are dura's node's.
        on_transition: told of every transition the node publishes (receive thread).

    Raises:
        BusError: DDS refused an endpoint.
    """

    def __init__(
        self,
        participant: Participant,
        library: TypeLibrary,
        node: str,
        *,
        discovery: Discovery | None = None,
        on_transition: TransitionListener | None = None,
    ) -> None:
        self.node = node
        self._get = ServiceClient(
            participant, library, f"{node}/get_state", "lifecycle_msgs/srv/GetState",
            discovery=discovery,
        )  # fmt: skip
        self._events: Reader | None = None
        try:
            self._change = ServiceClient(
                participant, library, f"{node}/change_state", "lifecycle_msgs/srv/ChangeState",
                discovery=discovery,
            )  # fmt: skip
        except BaseException:
            self._get.close()
            raise
        if on_transition is not None:
            decoder = library.decoder("lifecycle_msgs/msg/TransitionEvent")

            def heard(samples: list[Any], received: float) -> None:
                for data, info in samples:
                    if not info.valid_data:
                        continue
                    try:
                        event = decoder(data)
                    except CdrError as e:
                        log.warning("malformed transition event of %s: %s", node, e)
                        continue
                    on_transition(
                        str(event["transition"]["label"]),
                        STATES.get(int(event["start_state"]["id"]), "unknown"),
                        STATES.get(int(event["goal_state"]["id"]), "unknown"),
                    )

            self._events = participant.reader(
                dds_topic(f"{node}/transition_event"),
                library.idl("lifecycle_msgs/msg/TransitionEvent"),
                dds_qos(PROFILES["default"]),
                heard,
            )

    def wait(self, timeout: float) -> bool:
        """Wait until the node serves both services; whether it did within ``timeout`` s."""
        return self._get.wait(timeout) and self._change.wait(timeout)

    def state(self, *, timeout: float) -> str:
        """Ask the node for its state (``unconfigured``, ``inactive``, ``active`` ...).

        Raises:
            BusError: no answer within ``timeout`` seconds.
        """
        reply = self._get.call(timeout=timeout)
        return STATES.get(int(reply["current_state"]["id"]), "unknown")

    def transition(self, name: str, *, timeout: float) -> TransitionOutcome:
        """Ask for one transition (``configure``, ``activate`` ...) and say how it went.

        Raises:
            BusError: no answer within ``timeout`` seconds.
        """
        reply = self._change.call(
            {"transition": {"id": TRANSITIONS[name], "label": ""}}, timeout=timeout
        )
        return TransitionOutcome(name, bool(reply["success"]), self.state(timeout=timeout))

    def drive(self, command: str, *, timeout: float) -> TransitionOutcome | None:
        """Carry out one of dura's commands (:data:`DURA_TRANSITIONS`); the first failed
        transition, or the last one made (``None``: nothing to do in this state).

        Raises:
            BusError: the node did not answer within ``timeout`` seconds.
        """
        steps = DURA_TRANSITIONS[command].get(self.state(timeout=timeout), ())
        outcome = None
        for step in steps:
            outcome = self.transition(step, timeout=timeout)
            if not outcome.success:
                return outcome
        return outcome

    def close(self) -> None:
        self._get.close()
        self._change.close()
        if self._events is not None:
            self._events.close()
            self._events = None
