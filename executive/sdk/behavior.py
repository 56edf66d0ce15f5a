"""The behavior an author writes: :meth:`Behavior.execute` and its helpers.

A behavior carries out goals, one at a time, and returns their results. It owns the
author's side of a goal: watching the inputs a goal needs, waiting on running time,
feedback and resumable progress. The framework side (taking, cancelling and running
goals) is :mod:`executive.sdk.goal`.
"""

from __future__ import annotations

import time
from abc import ABC, abstractmethod
from collections.abc import Callable
from typing import Any, final

from executive.bus import keys
from executive.bus.message import Message
from executive.bus.payloads import GoalFeedback
from executive.bus.session import Bus
from executive.sdk.component import Component
from executive.sdk.goal import GoalCancelled, GoalFailed, GoalRunner, GoalTimedOut
from knowledge.description import Kind

__all__ = ["Behavior", "GoalCancelled", "GoalFailed", "GoalTimedOut"]

WAIT_STEP = 0.05  # seconds between two looks of Behavior.wait_until


class Behavior(Component, ABC):
    """A component that carries out goals, one at a time, and returns their results.

    :meth:`execute` runs on a thread of its own; it should call :meth:`checkpoint`
    (or :meth:`sleep`) often: that is where it waits while paused and where a
    cancellation or a stop reaches it.
    """

    kind = Kind.BEHAVIOR

    def __init__(self, name: str, bus: Bus) -> None:
        super().__init__(name, bus)
        self.latest: dict[str, dict[str, Any]] = {}
        self._input_timeout: dict[str, float] = {}
        self._heard: dict[str, float] = {}
        self._goal_runner = GoalRunner(self, self._framework)
        self._framework.goals = self._goal_runner

    @abstractmethod
    def execute(self, goal: dict[str, Any]) -> dict[str, Any] | None:
        """Carry out one goal and return the result's value; raise :class:`GoalFailed` to fail."""

    # --- helpers ----------------------------------------------------------------------

    @final
    def watch(self, *topics: str, timeout: float) -> None:
        """Watch inputs a goal needs (call in :meth:`on_start`). A goal waits for the
        first message of each before :meth:`execute` begins, so :attr:`latest` holds the
        newest payload of every watched topic from the first goal on (none within
        ``timeout`` seconds of the goal's start: the goal times out). Then
        :meth:`check_inputs` fails the goal when one of them has been silent for
        ``timeout`` seconds, counted from its last message, the goal's start and the last
        resume. Both are :class:`GoalTimedOut`: faults of the behavior."""

        def hearing(topic: str) -> Callable[[Message], None]:
            def heard(message: Message) -> None:
                self._heard[topic] = time.monotonic()
                self.latest[topic] = message.payload

            return heard

        for topic in topics:
            self._input_timeout[topic] = timeout
            self.subscribe(topic, hearing(topic))

    def _await_first_messages(self) -> None:
        """Wait until every watched input has sent a message (the framework calls it
        before :meth:`execute`).

        Raises:
            GoalTimedOut: an input sent none within its timeout of the goal's start.
        """
        waited = 0.0
        while missing := [t for t in self._input_timeout if t not in self.latest]:
            topic = missing[0]
            if waited > self._input_timeout[topic]:
                raise GoalTimedOut(
                    f"no {topic} yet: none came within {self._input_timeout[topic]:g} s"
                )
            self.sleep(WAIT_STEP)
            waited += WAIT_STEP

    @final
    def check_inputs(self) -> None:
        """Raise :class:`GoalFailed` if a watched input has gone silent."""
        now = time.monotonic()
        for topic, timeout in self._input_timeout.items():
            wall = now - max(self._heard.get(topic, 0.0), self._goal_runner.fresh_since)
            silent = self.clock.robot(wall)  # the timeout is robot time
            if silent > timeout:
                raise GoalTimedOut(f"no {topic} for {silent:.1f} s")

    @final
    def wait_until(self, condition: Callable[[], bool], timeout: float, what: str) -> None:
        """Wait (running time) until ``condition()`` holds, checking the watched inputs.

        Raises:
            GoalTimedOut: not within ``timeout`` seconds ("no <what> within ... s").
        """
        waited = 0.0
        while not condition():
            if waited > timeout:
                raise GoalTimedOut(f"no {what} within {timeout:g} s")
            self.sleep(WAIT_STEP)
            self.check_inputs()
            waited += WAIT_STEP

    @final
    def work_for(
        self,
        seconds: float,
        step: Callable[[float], None],
        *,
        job: str,
        rate: float = 10.0,
        store_every: float = 1.0,
    ) -> None:
        """Work for ``seconds`` of running time: call ``step(fraction_done)`` ``rate``
        times a second, check the watched inputs before each step, publish the progress
        as feedback and store it as the achievement ``progress`` every ``store_every``
        seconds. A behavior restarted on the same ``job`` (e.g. the same target) goes on
        from the stored progress: a warm start.
        """
        stored = self.achievements.get("progress")
        done = 0.0
        if isinstance(stored, dict) and stored.get("job") == job:
            done = float(stored.get("done", 0.0))
            self.log.info("warm start of %s at %.0f%%", job, done * 100)
        period = 1.0 / rate
        since_stored = 0.0
        while done < 1.0:
            self.sleep(period)
            self.check_inputs()
            done = min(1.0, done + period / seconds)
            step(done)
            self.feedback(job=job, done=round(done, 3))
            since_stored += period
            if since_stored >= store_every and done < 1.0:
                self.achieve("progress", {"job": job, "done": done})
                since_stored = 0.0
        self.achievements.pop("progress", None)  # the executive forgets it on success

    @final
    def feedback(self, **values: Any) -> None:
        """Publish feedback on the running goal (``component/<name>/feedback``)."""
        goal_id = self._goal_runner.goal_id
        if goal_id is None or self.faults.silent:
            return
        self.bus.publish(
            keys.component(self.name, "feedback"),
            GoalFeedback(self.name, goal_id, values).to_payload(),
        )

    @final
    def checkpoint(self) -> None:
        """Wait while paused; raise :class:`GoalCancelled` once cancelled or stopped."""
        self._goal_runner.checkpoint()

    @final
    def sleep(self, seconds: float) -> None:
        """Sleep ``seconds`` of running robot time (time paused does not count; with
        ``DURA_TIME_SCALE=N`` it takes 1/N of that on the wall clock)."""
        self._goal_runner.sleep(seconds)
