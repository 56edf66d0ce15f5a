"""A behavior's goals as ROS 2 action goals or service calls (run by the ROS 2 host).

A goal's fields name the action goal's (the service request's) fields by dotted path
(``pose.header.frame_id: map``); a value may be a whole message as a mapping (a
place's pose from the robot description's ``objects:``). Text where the message has a
number or a flag (``dura task start navigate --arg pose.pose.position.x=2``) is read
as one.

An action goal is sent with a fresh UUID; its feedback becomes the behavior's
feedback; the result's status decides: SUCCEEDED succeeds with the result, ABORTED and
CANCELED (by the server) fail with the result's fields as the reason. A pause cancels
the ROS 2 goal (ROS 2 actions cannot pause) and the resume sends it again; a
cancellation or stop of dura's goal cancels it. A server that leaves the graph while
a goal runs fails the goal. A service call succeeds with the response, unless the
response has ``success: false`` (std_srvs' convention): then it fails with its
``message``.
"""

from __future__ import annotations

import logging
import threading
import time
from collections.abc import Mapping
from concurrent import futures
from typing import Any

from rosbags.interfaces import Nodetype

from executive.ros2.action import ActionClient, ActionGoal, ActionGoalStatus
from executive.ros2.service_client import ServiceClient
from executive.ros2.types import TypeLibrary
from executive.sdk import Behavior, GoalCancelled, GoalFailed
from knowledge.errors import BusError, ConfigError

POLL = 0.05  # seconds between two looks for a cancellation while a goal runs
ANSWER = 5.0  # seconds a server gets to accept a goal or a cancellation
GONE = 2.0  # seconds without a server before a running goal fails
ENDING = 1.5  # seconds a cancelled goal gets to end on the server (a stop waits 2 s)
_NUMBERS = {"float32": float, "float64": float}
_TRUE, _FALSE = ("true", "1", "yes", "on"), ("false", "0", "no", "off")


def nested(goal: Mapping[str, Any]) -> dict[str, Any]:
    """Turn dotted goal fields into the nested dict of a message.

    Raises:
        GoalFailed: two fields overlap (``pose`` and ``pose.header``).
    """
    out: dict[str, Any] = {}
    for path in sorted(goal, key=lambda p: p.count(".")):
        *parents, last = path.split(".")
        at = out
        for part in parents:
            inner = at.setdefault(part, {})
            if not isinstance(inner, dict):
                raise GoalFailed(f"goal field '{path}' lies inside '{part}', which is a value")
            at = inner
        value = goal[path]
        if isinstance(at.get(last), dict) and isinstance(value, Mapping):
            at[last] = {**dict(value), **at[last]}
        else:
            at[last] = dict(value) if isinstance(value, Mapping) else value
    return out


def typed(library: TypeLibrary, message_type: str, values: Mapping[str, Any]) -> dict[str, Any]:
    """Read text as the number or flag a message field holds (nested messages included).

    Raises:
        GoalFailed: a field the type does not have, or text that is not its value.
    """
    fields = dict(library.fields(message_type))
    out: dict[str, Any] = {}
    for name, value in values.items():
        if name not in fields:
            raise GoalFailed(f"{message_type} has no field '{name}' (it has {', '.join(fields)})")
        kind, details = fields[name]
        if kind == Nodetype.NAME and isinstance(value, Mapping):
            out[name] = typed(library, details, value)
        elif kind == Nodetype.BASE and isinstance(value, str) and details[0] != "string":
            out[name] = _parse(name, details[0], value)
        else:
            out[name] = value
    return out


def _parse(name: str, base: str, text: str) -> Any:
    try:
        if base == "bool":
            if text.lower() not in (*_TRUE, *_FALSE):
                raise ValueError(text)
            return text.lower() in _TRUE
        return _NUMBERS.get(base, int)(text)
    except ValueError:
        raise GoalFailed(f"field '{name}' is a {base}, not '{text}'") from None


def _reason(verb: str, where: str, values: Mapping[str, Any]) -> str:
    shown = ", ".join(f"{k}={v!r}" for k, v in values.items() if v not in ("", 0, [], {}))
    return f"{where} {verb} the goal" + (f" ({shown[:200]})" if shown else "")


class ActionGoals:
    """Runs a behavior's goals as goals of one ROS 2 action."""

    def __init__(self, client: ActionClient, library: TypeLibrary, log: logging.Logger) -> None:
        self.client = client
        self.library = library
        self.log = log
        self._lock = threading.Lock()
        self._active: ActionGoal | None = None
        self._paused = False
        self._interrupted = False

    def execute(self, goal: Mapping[str, Any], behavior: Behavior) -> dict[str, Any]:
        """Carry out one goal (on the behavior's goal thread)."""
        action = self.client.action
        message = typed(self.library, f"{self.client.type}_Goal", nested(goal))
        while True:
            behavior.checkpoint()
            try:
                handle = self.client.send(
                    message, timeout=ANSWER, feedback=lambda f: behavior.feedback(**f)
                )
            except (BusError, ConfigError) as e:
                raise GoalFailed(f"cannot send the goal to {action}: {e}") from e
            if not handle.accepted:
                raise GoalFailed(f"{action} rejected the goal")
            self.log.info("%s accepted goal %s", action, handle.goal_id.hex())
            with self._lock:
                self._active, self._interrupted = handle, False
                paused = self._paused
            if paused:  # the pause came while the goal was on its way
                self._cancel(handle)
            try:
                result = self._wait(handle, behavior)
            finally:
                with self._lock:
                    self._active = None
                handle.forget()
            if result.status is ActionGoalStatus.SUCCEEDED:
                return {"status": "succeeded", "result": result.result}
            with self._lock:
                interrupted = self._interrupted
            if result.status is ActionGoalStatus.CANCELED and interrupted:
                self.log.info("goal %s cancelled for the pause; sent again", handle.goal_id.hex())
                continue  # checkpoint() waits for the resume
            verb = {ActionGoalStatus.ABORTED: "aborted", ActionGoalStatus.CANCELED: "cancelled"}
            raise GoalFailed(_reason(verb.get(result.status, "lost"), action, result.result))

    def _wait(self, handle: ActionGoal, behavior: Behavior) -> Any:
        missing_since: float | None = None
        try:
            while True:
                result = handle.result(POLL)
                if result is not None:
                    return result
                if self.client.ready():
                    missing_since = None
                elif missing_since is None:
                    missing_since = time.monotonic()
                elif time.monotonic() - missing_since > GONE:
                    raise GoalFailed(f"the server of {self.client.action} went away")
                with self._lock:
                    interrupted = self._interrupted
                if not interrupted:  # a cancelled goal's result comes while paused
                    behavior.checkpoint()
        except GoalCancelled:
            self._cancel(handle)
            handle.result(ENDING)  # the server is free again when dura's goal ends
            raise

    def _cancel(self, handle: ActionGoal) -> None:
        try:
            handle.cancel(ANSWER)
        except BusError as e:
            self.log.warning("cannot cancel goal %s of %s: %s", handle.goal_id.hex(),
                             self.client.action, e)  # fmt: skip

    def pause(self) -> None:
        """Cancel the running ROS 2 goal; it is sent again on resume."""
        with self._lock:
            self._paused = True
            handle = self._active
            if handle is not None:
                self._interrupted = True
        if handle is not None:
            self._cancel(handle)

    def resume(self) -> None:
        with self._lock:
            self._paused = False


class ServiceGoals:
    """Runs a behavior's goals as calls of one ROS 2 service."""

    def __init__(self, client: ServiceClient, library: TypeLibrary) -> None:
        self.client = client
        self.library = library

    def execute(self, goal: Mapping[str, Any], behavior: Behavior) -> dict[str, Any]:
        """Call the service once (on the behavior's goal thread)."""
        service = self.client.service
        request = typed(self.library, self.client.request_type, nested(goal))
        try:
            future = self.client.call_async(request)
        except (BusError, ConfigError) as e:
            raise GoalFailed(f"cannot call {service}: {e}") from e
        while not future.done():
            behavior.checkpoint()  # a cancellation drops the call: services cannot cancel
            futures.wait([future], timeout=POLL)
        try:
            response = future.result()
        except BusError as e:
            raise GoalFailed(str(e)) from e
        if response.get("success") is False:
            raise GoalFailed(f"{service}: {response.get('message') or 'success: false'}")
        return {"response": response}
