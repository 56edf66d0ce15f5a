"""Which robots of a fleet can act now, and why the others cannot.

A robot is available while its executive is there (its liveliness token) and its steps
do not keep failing: after ``max_failures`` failed steps in a row it is unavailable
until its executive joins again (restarted, or back on the network). A robot not seen
yet is unavailable too, and so is every object of the robot type that is no robot of
the fleet (``outside``). The planner plans only with available robots
(:mod:`executive.planning.unavailable`); who asks is told each change.
"""

from __future__ import annotations

import threading
from collections.abc import Callable, Collection, Mapping

NOT_SEEN = "its executive has not been seen yet"


class Availability:
    """The fleet's robots and whether each can act (thread-safe).

    Args:
        objects: each robot's PDDL object, by robot name.
        max_failures: failed steps in a row that make a robot unavailable.
        changed: told ``(robot, available, reason)`` on each change, outside the lock.
        outside: the objects of the robot type that are no robot of the fleet.
    """

    def __init__(
        self,
        objects: Mapping[str, str],
        max_failures: int,
        changed: Callable[[str, bool, str], None] = lambda robot, available, reason: None,
        outside: Collection[str] = (),
    ) -> None:
        self.objects = dict(objects)
        self.outside = frozenset(outside)
        self.max_failures = max_failures
        self.changed = changed
        self._lock = threading.Lock()
        self._why: dict[str, str | None] = dict.fromkeys(objects, NOT_SEEN)  # None: available
        self._failures: dict[str, int] = dict.fromkeys(objects, 0)

    def reason(self, robot: str) -> str | None:
        """Why a robot cannot act now (``None``: it can)."""
        with self._lock:
            return self._why[robot]

    def snapshot(self) -> dict[str, str | None]:
        """Each robot and why it cannot act (``None``: it can)."""
        with self._lock:
            return dict(self._why)

    def unavailable_objects(self) -> frozenset[str]:
        """The PDDL objects of the robots that cannot act now."""
        with self._lock:
            gone = {self.objects[r] for r, why in self._why.items() if why is not None}
        return self.outside | gone

    def joined(self, robot: str) -> None:
        """Its executive is there (again): it can act, its failures forgotten."""
        self._set(robot, None, reset=True)

    def lost(self, robot: str, reason: str) -> None:
        """Its executive vanished."""
        self._set(robot, reason, reset=True)

    def step_succeeded(self, robot: str) -> None:
        with self._lock:
            self._failures[robot] = 0

    def step_failed(self, robot: str, reason: str) -> None:
        """A step of it failed: at ``max_failures`` in a row it is unavailable."""
        with self._lock:
            self._failures[robot] += 1
            count = self._failures[robot]
        if count >= self.max_failures:
            self._set(robot, f"its last {count} steps failed, the last because {reason}")

    def _set(self, robot: str, why: str | None, *, reset: bool = False) -> None:
        with self._lock:
            before = self._why[robot]
            self._why[robot] = why
            if reset:
                self._failures[robot] = 0
        if (before is None) != (why is None):
            self.changed(robot, why is None, why or "")
