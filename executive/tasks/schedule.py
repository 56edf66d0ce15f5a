"""What the scheduler is asked and what it answers: requests, assignments, results.

Times are seconds relative to the moment the schedule is computed ("now").
"""

from __future__ import annotations

import enum
from collections.abc import Mapping
from dataclasses import dataclass, field


@dataclass(frozen=True)
class Request:
    """A task's request for a system configuration, with its constraints.

    A running task is a request too (``running=True``): it keeps start 0 and, as far
    as possible, its ``configuration``; its ``duration`` is what remains of it.

    Args:
        id: the task's id, unique among the requests of one schedule.
        behavior: the behavior the task runs (one process: one task at a time).
        needs: the capabilities the behavior requires.
        duration: expected duration in seconds (> 0).
        earliest: earliest start.
        deadline: latest end, or ``None``.
        together: ids of requests that must start at the same time as this one.
        running: the task runs now.
        configuration: a running task's providers now, capability → functionality.
    """

    id: str
    behavior: str
    needs: tuple[str, ...]
    duration: float
    earliest: float = 0.0
    deadline: float | None = None
    together: tuple[str, ...] = ()
    running: bool = False
    configuration: Mapping[str, str] = field(default_factory=dict)

    def __post_init__(self) -> None:
        if not self.duration > 0:
            raise ValueError(f"request '{self.id}': duration must be positive, not {self.duration}")
        if self.earliest < 0:
            raise ValueError(f"request '{self.id}': earliest start {self.earliest} is in the past")
        if self.configuration and not self.running:
            raise ValueError(f"request '{self.id}': only a running task has a configuration")


@dataclass(frozen=True)
class Assignment:
    """When a request runs and which functionality provides each capability it needs.

    ``providers`` is closed under ``requires``: it holds the behavior's capabilities
    and those the chosen functionalities require. ``after`` names the requests that
    must end before this one starts (they share a non-shareable functionality or the
    behavior).
    """

    request: str
    start: float
    end: float
    providers: Mapping[str, str]
    after: frozenset[str] = frozenset()

    @property
    def functionalities(self) -> frozenset[str]:
        return frozenset(self.providers.values())


class ScheduleStatus(enum.Enum):
    OPTIMAL = "optimal"  # the best schedule, proven
    FEASIBLE = "feasible"  # the best schedule found within the time limit
    TIMEOUT = "timeout"  # no schedule found within the time limit


@dataclass(frozen=True)
class ScheduleResult:
    """A schedule: an assignment for every request that can run, a reason for every other.

    Args:
        status: how good the schedule is known to be.
        assignments: by request id, in order of start.
        cancelled: request id → why it cannot be scheduled.
        cost: the optimisation cost by level, most important first (see
            ``executive.tasks.scheduler.COSTS``).
        solve_time: seconds spent, grounding and explanations included.
    """

    status: ScheduleStatus
    assignments: Mapping[str, Assignment] = field(default_factory=dict)
    cancelled: Mapping[str, str] = field(default_factory=dict)
    cost: Mapping[str, int] = field(default_factory=dict)
    solve_time: float = 0.0

    @property
    def complete(self) -> bool:
        """Every request is scheduled."""
        return self.status is not ScheduleStatus.TIMEOUT and not self.cancelled
