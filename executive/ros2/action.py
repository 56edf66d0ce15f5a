"""A client of one ROS 2 action over DDS: goals sent, followed and cancelled as rclpy does.

An action ``/navigate`` is three services and two topics under ``/navigate/_action/``
(:func:`executive.ros2.names.action_names`). A goal gets a random 16-byte UUID.
``send_goal`` (``<type>_SendGoal``) carries the UUID and the goal and answers whether
the server accepted it; ``get_result`` (``<type>_GetResult``), asked as soon as the goal
is accepted, answers when the goal has ended, with its final status and result;
``feedback`` (``<type>_FeedbackMessage``) carries the feedback of every goal, told apart
by UUID; ``cancel_goal`` (``action_msgs/srv/CancelGoal``) asks the server to cancel one.
The ``status`` topic is not needed: the result carries the final status.
"""

from __future__ import annotations

import enum
import logging
import threading
import time
import uuid
from collections.abc import Callable, Mapping
from concurrent.futures import Future
from concurrent.futures import TimeoutError as FutureTimeout
from dataclasses import dataclass, field
from typing import Any

from executive.ros2.cdr import CdrError
from executive.ros2.discovery import Discovery
from executive.ros2.names import action_names, dds_topic
from executive.ros2.participant import Participant, Reader
from executive.ros2.qos import dds_qos
from executive.ros2.service_client import ServiceClient
from executive.ros2.types import TypeLibrary
from knowledge.ros2_spec import PROFILES

log = logging.getLogger("dura.ros2")

CANCEL_GOAL = "action_msgs/srv/CancelGoal"
Feedback = Callable[[dict[str, Any]], None]


class ActionGoalStatus(enum.IntEnum):
    """The states of a ROS 2 action goal (action_msgs/msg/GoalStatus)."""

    UNKNOWN = 0
    ACCEPTED = 1
    EXECUTING = 2
    CANCELING = 3
    SUCCEEDED = 4
    CANCELED = 5
    ABORTED = 6


class CancelReturn(enum.IntEnum):
    """What a server answers to a cancellation (action_msgs/srv/CancelGoal)."""

    NONE = 0  # cancelling
    REJECTED = 1
    UNKNOWN_GOAL_ID = 2
    GOAL_TERMINATED = 3


@dataclass(frozen=True)
class ActionResult:
    """How a goal ended: its final status and the result message as a dict."""

    status: ActionGoalStatus
    result: dict[str, Any] = field(default_factory=dict)


class ActionGoal:
    """One goal sent to an action server, accepted or not."""

    def __init__(
        self,
        client: ActionClient,
        goal_id: bytes,
        accepted: bool,
        result: Future[dict[str, Any]] | None,
    ) -> None:
        self.client = client
        self.goal_id = goal_id
        self.accepted = accepted
        self._result = result

    def done(self) -> bool:
        """Tell whether the goal has ended (a rejected goal never ran)."""
        return self._result is None or self._result.done()

    def result(self, timeout: float | None = None) -> ActionResult | None:
        """Wait for the goal's end; its result (``None``: not within ``timeout`` s).

        Raises:
            BusError: the client was closed, or the reply was malformed.
        """
        if self._result is None:
            return ActionResult(ActionGoalStatus.UNKNOWN)
        try:
            reply = self._result.result(timeout)
        except FutureTimeout:
            return None
        try:
            status = ActionGoalStatus(int(reply["status"]))
        except ValueError:
            status = ActionGoalStatus.UNKNOWN
        return ActionResult(status, dict(reply.get("result") or {}))

    def cancel(self, timeout: float) -> CancelReturn:
        """Ask the server to cancel the goal; its answer.

        Raises:
            BusError: no answer within ``timeout`` seconds.
        """
        reply = self.client._cancel.call(
            {"goal_info": {"goal_id": {"uuid": list(self.goal_id)}}}, timeout=timeout
        )
        try:
            return CancelReturn(int(reply["return_code"]))
        except ValueError:
            return CancelReturn.REJECTED

    def forget(self) -> None:
        """Stop delivering this goal's feedback."""
        self.client._forget(self.goal_id)


class ActionClient:
    """Sends goals to one ROS 2 action and follows them.

    Args:
        participant: the DDS participant to act from.
        library: the message types (``<type>_SendGoal_Request`` ...).
        action: the action's name, e.g. ``/navigate_to_pose``.
        action_type: e.g. ``nav2_msgs/action/NavigateToPose``.
        discovery: when given, the client's endpoints are dura's node's.

    Raises:
        ConfigError: an unknown action type.
        BusError: DDS refused an endpoint.
    """

    def __init__(
        self,
        participant: Participant,
        library: TypeLibrary,
        action: str,
        action_type: str,
        *,
        discovery: Discovery | None = None,
    ) -> None:
        names = action_names(action)
        self.action = action
        self.type = action_type
        self.library = library
        self._feedback_decoder = library.decoder(f"{action_type}_FeedbackMessage")
        self._lock = threading.Lock()
        self._listeners: dict[bytes, Feedback] = {}
        self._clients: list[ServiceClient] = []
        self._feedback: Reader | None = None
        self._discovery = discovery
        try:
            for service, kind in ((names.send_goal, f"{action_type}_SendGoal"),
                                  (names.get_result, f"{action_type}_GetResult"),
                                  (names.cancel_goal, CANCEL_GOAL)):  # fmt: skip
                self._clients.append(
                    ServiceClient(participant, library, service, kind, discovery=discovery)
                )
            self._feedback = participant.reader(
                dds_topic(names.feedback),
                library.idl(f"{action_type}_FeedbackMessage"),
                dds_qos(PROFILES["default"]),
                self._on_feedback,
            )
        except BaseException:
            self.close()
            raise
        self._send, self._get_result, self._cancel = self._clients
        if discovery is not None:
            discovery.declare(self._feedback.guid, writer=False)

    def ready(self) -> bool:
        """Tell whether a server answers all three services."""
        return all(c.ready() for c in self._clients)

    def wait(self, timeout: float) -> bool:
        """Wait until a server is there; whether it came within ``timeout`` seconds."""
        deadline = time.monotonic() + timeout
        return all(c.wait(max(0.0, deadline - time.monotonic())) for c in self._clients)

    def send(
        self, goal: Mapping[str, Any], *, timeout: float, feedback: Feedback | None = None
    ) -> ActionGoal:
        """Send a goal and wait for the server to accept or reject it; once accepted, ask
        for its result. ``feedback`` gets each feedback message (on the receive thread).

        Raises:
            ConfigError: a field the goal type does not have.
            BusError: no answer within ``timeout`` seconds.
        """
        goal_id = uuid.uuid4().bytes
        if feedback is not None:
            with self._lock:
                self._listeners[goal_id] = feedback
        uuid_field = {"uuid": list(goal_id)}
        try:
            reply = self._send.call({"goal_id": uuid_field, "goal": dict(goal)}, timeout=timeout)
        except BaseException:
            self._forget(goal_id)
            raise
        if not reply.get("accepted"):
            self._forget(goal_id)
            return ActionGoal(self, goal_id, False, None)
        result = self._get_result.call_async({"goal_id": uuid_field})
        return ActionGoal(self, goal_id, True, result)

    def _forget(self, goal_id: bytes) -> None:
        with self._lock:
            self._listeners.pop(goal_id, None)

    def _on_feedback(self, samples: list[Any], received: float) -> None:
        for data, info in samples:
            if not info.valid_data:
                continue
            try:
                message = self._feedback_decoder(data)
            except CdrError as e:
                log.warning("malformed feedback of ROS 2 action %s: %s", self.action, e)
                continue
            goal_id = bytes(message["goal_id"]["uuid"])
            with self._lock:
                listener = self._listeners.get(goal_id)
            if listener is not None:
                try:
                    listener(message["feedback"])
                except Exception:
                    log.exception("a feedback listener of %s failed", self.action)

    def close(self) -> None:
        """Delete the client's endpoints; goals waiting for a result get a BusError."""
        with self._lock:
            self._listeners.clear()
        for client in self._clients:
            client.close()
        self._clients = []
        if self._feedback is not None:
            if self._discovery is not None and not self._discovery.participant.closed:
                self._discovery.retract(self._feedback.guid)
            self._feedback.close()
            self._feedback = None
