"""The integrity goals' thread: it checks the integrity rules
(:mod:`executive.planning.integrity`) when something they read changed (an event, a
diagnosis) and when a rule waiting ``for`` its trigger is due, and it replans when a
permanent fault came or went and so a task can no longer run, or can run again
(:mod:`executive.planning.blocked_tasks`)."""

from __future__ import annotations

import logging
import threading
from collections.abc import Mapping
from typing import Any

from executive.bus.clock import Clock
from executive.planning.blocked_tasks import BlockedTasks
from executive.planning.goal_planner import GoalPlanner
from executive.planning.integrity import IntegrityGoals

log = logging.getLogger("dura.high_level")
FAULT_CHANGES = ("PERMANENT_FAULT", "COMPONENT_RESET")  # events that may block or free tasks


class IntegrityLoop:
    """Runs the integrity goals and the blocked-task detection on a thread of its own.

    Args:
        integrity: the rules and the goals they post.
        goals: told of every goal posted, and to replan when the blocked tasks change.
        blocked: the blocked tasks, as they were when the loop was built.
        clock: robot time (rules wait ``for`` robot seconds).
    """

    def __init__(
        self, integrity: IntegrityGoals, goals: GoalPlanner, blocked: BlockedTasks, clock: Clock
    ) -> None:
        self.integrity = integrity
        self.goals = goals
        self.blocked = blocked
        self.clock = clock
        self._check = threading.Event()  # something changed: check the rules
        self._faults_changed = threading.Event()  # a permanent fault came or went
        self._stopping = threading.Event()
        self._thread = threading.Thread(target=self._run, name="integrity-goals", daemon=True)

    def start(self) -> None:
        """Check at once, then whenever something changes."""
        self._check.set()
        self._thread.start()

    def stop(self) -> None:
        self._stopping.set()
        self._check.set()
        if self._thread.ident is not None:  # it had started
            self._thread.join()

    def changed(self, kind: str) -> None:
        """An event of ``kind`` was logged (by this process or another)."""
        if kind in FAULT_CHANGES:
            self._faults_changed.set()
        if not kind.startswith("INTEGRITY_"):
            self._check.set()

    def diagnosed(self, payload: Mapping[str, Any]) -> None:
        """A new diagnosis result (a ``diagnoses`` payload)."""
        self.integrity.diagnosed(payload)
        self._check.set()

    def _run(self) -> None:
        while not self._stopping.is_set():
            due = self.integrity.next_check()
            wait = None if due is None else max(0.0, self.clock.wall(due - self.clock.monotonic()))
            self._check.wait(wait)
            self._check.clear()
            if self._stopping.is_set():
                return
            try:
                posted = self.integrity.check()
            except Exception:  # a broken check must not end the generator
                log.exception("integrity check failed")
                continue
            for goal in posted:
                self.goals.wake(f"integrity goal {goal.id} posted")
            if self._faults_changed.is_set():
                self._faults_changed.clear()
                reason = self.blocked.change()
                if reason is not None:
                    self.goals.replan(reason)
