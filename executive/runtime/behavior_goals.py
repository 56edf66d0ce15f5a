"""The behavior goal protocol: goals sent to behaviors, their feedback and results.

A goal goes to a ready behavior as a ``goal`` command; the behavior answers at once and
later publishes feedback on ``component/<name>/feedback`` and one result on
``component/<name>/result``. A goal's :class:`GoalHandle` hears both. Every result is
stored in the KB as a return value (with the task it served); a success also clears the
behavior's achievements, which behaviors store through ``component/achieve`` while they
work, for a warm start after a restart. When a behavior's process ends with goals still
open, their results are made here: CANCELLED if it was asked to stop, else FAILED.
"""

from __future__ import annotations

import contextlib
import logging
import threading
import time
import uuid
from collections.abc import Callable, Mapping
from typing import Any

from executive.bus import keys
from executive.bus.api.components import COMPONENT_ACHIEVE, Achievement
from executive.bus.message import Message
from executive.bus.payloads import GoalFeedback, GoalResult
from executive.bus.schema import PayloadError
from executive.bus.session import Bus
from executive.bus.states import Command, GoalStatus
from executive.bus.verb import Empty
from executive.runtime.states import call_safely
from knowledge.description import ComponentSpec, Kind, RobotDescription
from knowledge.errors import ComponentError
from knowledge.knowledge_base import KnowledgeBase

log = logging.getLogger("dura.launcher")

CommandSender = Callable[..., dict[str, Any]]
"""``command(component, verb, **fields)``: a lifecycle command to a running component."""


class GoalHandle:
    """A goal sent to a behavior: its feedback as it comes, and its result."""

    def __init__(
        self,
        command: CommandSender,
        component: str,
        goal_id: str,
        goal: Mapping[str, Any],
        task_id: int | None,
    ) -> None:
        self.component = component
        self.goal_id = goal_id
        self.goal = dict(goal)
        self.task_id = task_id
        self.feedback: dict[str, Any] = {}
        self._command = command
        self._result: GoalResult | None = None
        self._done = threading.Event()
        self._lock = threading.Lock()
        self._feedback_listeners: list[Callable[[dict[str, Any]], None]] = []
        self._done_callbacks: list[Callable[[GoalResult], None]] = []

    @property
    def result(self) -> GoalResult | None:
        """The result, once the goal has ended."""
        return self._result

    def done(self) -> bool:
        return self._done.is_set()

    def wait(self, timeout: float | None = None) -> GoalResult | None:
        """Wait for the result; None if the goal has not ended within ``timeout``."""
        self._done.wait(timeout)
        return self._result

    def cancel(self) -> None:
        """Ask the behavior to cancel the goal (the result says CANCELLED)."""
        self._command(self.component, Command.CANCEL, goal_id=self.goal_id)

    def add_feedback_listener(self, listener: Callable[[dict[str, Any]], None]) -> None:
        with self._lock:
            self._feedback_listeners.append(listener)

    def add_done_callback(self, callback: Callable[[GoalResult], None]) -> None:
        """Call ``callback(result)`` when the goal ends (at once if it has)."""
        with self._lock:
            if self._result is None:
                self._done_callbacks.append(callback)
                return
            result = self._result
        callback(result)

    def _feedback(self, feedback: dict[str, Any]) -> None:
        self.feedback = feedback
        with self._lock:
            listeners = list(self._feedback_listeners)
        for listener in listeners:
            call_safely(listener, feedback)

    def _resolve(self, result: GoalResult) -> bool:
        with self._lock:
            if self._result is not None:
                return False
            self._result = result
            callbacks, self._done_callbacks = self._done_callbacks, []
        self._done.set()
        for callback in callbacks:
            call_safely(callback, result)
        return True


class BehaviorGoals:
    """The open goals of the robot's behaviors, and what their results leave in the KB.

    Args:
        command: sends a lifecycle command to a running component (the lifecycle's).
    """

    def __init__(
        self, robot: RobotDescription, bus: Bus, kb: KnowledgeBase, *, command: CommandSender
    ) -> None:
        self.robot = robot
        self.bus = bus
        self.kb = kb
        self._command = command
        self._lock = threading.Lock()
        self._open: dict[str, dict[str, GoalHandle]] = {name: {} for name in robot.components}
        self._declared: list[Any] = []

    def open(self) -> None:
        self._declared = [
            self.bus.subscribe(keys.component("*", "result"), self._on_result),
            self.bus.subscribe(keys.component("*", "feedback"), self._on_feedback),
            COMPONENT_ACHIEVE.serve(self.bus, self._on_achieve),
        ]

    def close(self) -> None:
        for entity in self._declared:
            with contextlib.suppress(Exception):
                entity.undeclare()
        self._declared = []

    def send(
        self, spec: ComponentSpec, goal: Mapping[str, Any], *, task_id: int | None
    ) -> GoalHandle:
        """Send a goal to a ready behavior; its result comes through the handle.

        Raises:
            ComponentError: not a behavior, not ready, or it refused the goal (busy).
        """
        name = spec.name
        if spec.kind is not Kind.BEHAVIOR:
            raise ComponentError(f"'{name}' is a functionality: it takes no goals")
        handle = GoalHandle(self._command, name, uuid.uuid4().hex[:12], goal, task_id)
        with self._lock:
            self._open[name][handle.goal_id] = handle
        try:
            self._command(name, Command.GOAL, goal_id=handle.goal_id, goal=handle.goal)
        except ComponentError:
            with self._lock:
                del self._open[name][handle.goal_id]
            raise
        return handle

    def process_ended(self, component: str, stopping: bool, how: str) -> None:
        """End the goals a behavior's ended process left open."""
        with self._lock:
            handles = list(self._open[component].values())
        status = GoalStatus.CANCELLED if stopping else GoalStatus.FAILED
        for handle in handles:
            reason = f"'{component}' {how}"
            self._finish(GoalResult(component, handle.goal_id, status, {}, reason, time.time()))

    def _on_result(self, message: Message) -> None:
        try:
            result = GoalResult.from_payload(message.payload)
        except (KeyError, ValueError, TypeError) as e:
            log.warning("malformed result on %s: %s", message.key, e)
            return
        if self._sent_by_itself(message, result.component):
            self._finish(result)

    def _sent_by_itself(self, message: Message, named: str) -> bool:
        """Whether a message on ``component/<name>/...`` speaks of that component: the
        key is what access control checks (only its own login publishes there), the
        payload's ``component`` is what the sender wrote."""
        sender = message.key.split("/")[1]
        if sender not in self._open:
            return False
        if named != sender:
            log.warning(
                "refused a message on %s about '%s': a component speaks only for itself",
                message.key,
                named[:64],
            )
            return False
        return True

    def _finish(self, result: GoalResult) -> None:
        """Resolve the goal's handle (once) and store the result in the KB."""
        name = result.component
        with self._lock:
            handle = self._open[name].pop(result.goal_id, None)
        if handle is not None and not handle._resolve(result):
            return
        task_id = handle.task_id if handle is not None else None
        with self.kb.transaction():
            self.kb.store_return_value(name, result.to_payload(), task_id=task_id)
            self.kb.log_event(
                f"GOAL_RESULT_{result.status.name}",
                name,
                {"goal_id": result.goal_id, "reason": result.reason},
            )
            if result.status is GoalStatus.SUCCEEDED:
                self.kb.clear_achievements(name)

    def _on_feedback(self, message: Message) -> None:
        try:
            feedback = GoalFeedback.from_payload(message.payload)
        except PayloadError as e:
            log.warning("malformed feedback on %s: %s", message.key, e)
            return
        if not self._sent_by_itself(message, feedback.component):
            return
        with self._lock:
            handle = self._open[feedback.component].get(feedback.goal_id)
        if handle is not None:
            handle._feedback(feedback.feedback)

    def _on_achieve(self, achievement: Achievement) -> Empty:
        name = achievement.component
        if name not in self._open:
            raise ComponentError(f"achievement for unknown component {name!r}")
        self.kb.set_achievement(name, achievement.key, achievement.value)
        return Empty()
