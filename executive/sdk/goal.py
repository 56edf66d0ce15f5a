"""A behavior's goals, the framework side: one at a time, each on a thread of its own.

A goal command starts :meth:`Behavior.execute <executive.sdk.behavior.Behavior.execute>`
on a new thread; what it returns, raises or is cancelled with becomes the goal's
result on ``component/<name>/result``. :class:`GoalFailed`, :class:`GoalTimedOut` and
:class:`GoalCancelled` are what an author raises and meets.

A goal fails in one of two ways, and the executive treats them apart:

- **in the world**: :class:`GoalFailed` says the goal cannot be done as the world is
  (the door is locked, the object is not there). The plan's step fails and the planner
  plans again; the behavior is not at fault: it is neither restarted nor counted faulty.
- **as a fault**: any other exception escaping ``execute``, a crash of the process, and
  :class:`GoalTimedOut` (an input gone silent, a condition never met in time). The
  behavior is restarted up to its ``max_restarts``, its faults are counted, and beyond
  them its task fails and the planner plans again without it.
"""

from __future__ import annotations

import json
import threading
import time
from typing import TYPE_CHECKING, Any

from executive.bus import keys
from executive.bus.payloads import GoalResult
from executive.bus.states import GoalStatus
from knowledge.errors import ComponentError

if TYPE_CHECKING:
    from executive.sdk.behavior import Behavior
    from executive.sdk.framework import Framework


class GoalFailed(Exception):
    """Raise in :meth:`Behavior.execute` when the goal cannot be done in the world as it
    is; the message is the reason. The step fails and the planner plans again: not a
    fault of the behavior (no restart, no fault counted)."""


class GoalTimedOut(GoalFailed):
    """The goal waited too long: a watched input went silent, or
    :meth:`Behavior.wait_until`'s condition did not come true in time. A fault, as an
    exception or a crash is: the behavior is restarted and its faults are counted."""


class GoalCancelled(Exception):
    """Raised by :meth:`Behavior.checkpoint` once the goal is cancelled or stopped."""


class GoalRunner:
    """Takes, cancels and runs a behavior's goals, and publishes their results.

    Attributes:
        goal_id: the running goal's, or None.
        fresh_since: when the behavior's watched inputs last got their timeout afresh
            (the goal's start, the last resume).
    """

    def __init__(self, behavior: Behavior, framework: Framework) -> None:
        self.behavior = behavior
        self.framework = framework
        self.goal_id: str | None = None
        self.fresh_since = time.monotonic()
        self._cancelled = False
        self._thread: threading.Thread | None = None

    def take(self, goal_id: str, goal: dict[str, Any]) -> None:
        name, framework = self.behavior.name, self.framework
        if not framework.running:
            raise ComponentError(f"'{name}' is {framework.phase.value}: it takes no goal now")
        if self.goal_id is not None:
            raise ComponentError(f"'{name}' is busy with goal {self.goal_id}")
        with framework.changed:
            self.goal_id, self._cancelled = goal_id, False
        self._thread = threading.Thread(
            target=self._run, args=(goal_id, goal), daemon=True, name=f"goal-{goal_id}"
        )
        self._thread.start()

    def cancel(self, goal_id: str) -> None:
        if goal_id != self.goal_id:
            raise ComponentError(f"'{self.behavior.name}' has no running goal {goal_id!r}")
        with self.framework.changed:
            self._cancelled = True
            self.framework.changed.notify_all()

    def resumed(self) -> None:
        self.fresh_since = time.monotonic()  # inputs get their timeout again

    def join(self, timeout: float) -> None:
        thread = self._thread
        if thread is not None:
            thread.join(timeout)

    def checkpoint(self) -> None:
        """Wait while paused; raise :class:`GoalCancelled` once cancelled or stopped."""
        framework = self.framework
        with framework.changed:
            framework.changed.wait_for(
                lambda: framework.running or framework.ended or self._cancelled
            )
            if framework.ended or self._cancelled:
                raise GoalCancelled("stopped" if framework.ended else "cancelled")

    def sleep(self, seconds: float) -> None:
        """Sleep ``seconds`` of running robot time (time paused does not count)."""
        framework = self.framework
        remaining = self.behavior.clock.wall(seconds)
        while True:
            self.checkpoint()
            if remaining <= 0:
                return
            began = time.monotonic()
            framework.wait(lambda: not framework.running or self._cancelled, timeout=remaining)
            remaining -= time.monotonic() - began

    def _run(self, goal_id: str, goal: dict[str, Any]) -> None:
        behavior = self.behavior
        status, value, reason, fault = GoalStatus.FAILED, {}, "", True
        self.fresh_since = time.monotonic()
        try:
            behavior._await_first_messages()
            returned = behavior.execute(goal)
            if returned is not None and not isinstance(returned, dict):
                raise GoalFailed(f"execute returned a {type(returned).__name__}, not a dict")
            json.dumps(returned)
            status, value = GoalStatus.SUCCEEDED, returned or {}
        except GoalCancelled as e:
            status, reason = GoalStatus.CANCELLED, str(e)
        except GoalFailed as e:
            reason, fault = str(e), isinstance(e, GoalTimedOut)
            behavior.log.warning("goal %s failed: %s", goal_id, reason)
        except Exception as e:
            # the traceback is in the component's log: say where
            reason = f"{type(e).__name__}: {e} (dura component logs {behavior.name})"
            behavior.log.exception("goal %s failed", goal_id)
        with self.framework.changed:
            self.goal_id = None
        result = GoalResult(behavior.name, goal_id, status, value, reason, time.time(), fault)
        behavior.bus.publish(keys.component(behavior.name, "result"), result.to_payload())
