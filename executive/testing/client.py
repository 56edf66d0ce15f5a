"""What a test asks of a running robot over the bus, and waits for: goals, facts, events,
components, faults and status, as typed records.

:class:`RobotClient` is the bus side of the ``dura_robot`` fixture's
:class:`~executive.testing.harness.RobotProcess` (which adds the executive's process):
every helper calls one verb of :mod:`executive.bus.api` and returns what it answers, a
goal as a :class:`~knowledge.records.Goal`, an event as an
:class:`~knowledge.records.Event`, a component as a
:class:`~executive.bus.api.components.ComponentEntry`, ``status()`` as a
:class:`~executive.bus.api.planning.StatusReply`. The ``wait_*`` helpers ask again until
what the test waits for is there, and fail it (an ``AssertionError``) with the latest
events when it does not come.

Earlier versions returned dicts: ``record["key"]`` still reads a field (as the dict held
it, in JSON form), with a DeprecationWarning naming the attribute to use.
"""

from __future__ import annotations

import time
from abc import ABC, abstractmethod
from collections.abc import Mapping
from typing import Any

from executive.bus.api import planning
from executive.bus.api.components import COMPONENT_INJECT, COMPONENT_LIST, Injection
from executive.bus.keys import api
from executive.bus.reports import ComponentEntry
from executive.bus.session import Bus
from executive.bus.states import Lifecycle
from knowledge.description import RobotDescription
from knowledge.errors import BusError, DuraError
from knowledge.records import Event, Goal, GoalState, TimedFact

INJECT_TIMEOUT = 30.0  # seconds a fault injection waits for its component to run
POLL = 0.05  # seconds between two looks of a wait


class GoalEnded(AssertionError):
    """A goal ended other than expected, or did not end in time (a test failure)."""


class WaitTimedOut(AssertionError):
    """What a test waited for did not happen in time (a test failure)."""


class RobotClient(ABC):
    """A running robot's executive as a test talks to it (see the module docstring).

    Subclasses give the robot's description (``robot``) and the bus session (``bus``).
    """

    robot: RobotDescription

    @property
    @abstractmethod
    def bus(self) -> Bus:
        """A session with the robot's executive (an operator's)."""

    def request(
        self, verb: str, payload: Mapping[str, Any] | None = None, timeout: float = 30.0
    ) -> dict[str, Any]:
        """Ask the executive (``executive/api/<verb>``); raises BusError on an error reply."""
        return self.bus.request(api(verb), dict(payload or {}), timeout=timeout)

    # --- goals ---------------------------------------------------------------------------

    def submit_goal(
        self,
        expression: str,
        *,
        priority: int = 0,
        deadline: float | None = None,
        keep: bool = False,
    ) -> int:
        """Submit a goal (``keep``: a maintenance goal); returns its id. Raises BusError if
        the executive refuses it."""
        request = planning.GoalAdd(expression, priority, deadline, keep=keep)
        return planning.GOAL_ADD.call(self.bus, request).goal.id

    def goal(self, goal_id: int) -> Goal:
        return planning.GOAL_SHOW.call(self.bus, planning.GoalId(goal_id)).goal

    def goals(self) -> list[Goal]:
        """Every goal, oldest first, however many (asked for a page at a time)."""
        return planning.newest_goals(self.bus)

    def cancel_goal(self, goal_id: int) -> None:
        planning.GOAL_CANCEL.call(self.bus, planning.GoalId(goal_id))

    def wait_for(
        self, goal_id: int, state: str | GoalState = GoalState.ACHIEVED, timeout: float = 60.0
    ) -> Goal:
        """Wait until a goal is in ``state``; returns the goal.

        Raises:
            GoalEnded: the goal ended in another state, or ``timeout`` passed (the
                message has the goal's state and reason and the latest events).
        """
        wanted = GoalState(state)
        deadline = time.monotonic() + timeout
        while True:
            goal = self.goal(goal_id)
            if goal.state is wanted:
                return goal
            ended = not goal.state.is_open and goal.state is not GoalState.UNREACHABLE
            if ended or time.monotonic() > deadline:
                why = f": {goal.reason}" if goal.reason else ""
                raise GoalEnded(
                    f"goal {goal_id} {goal.expression} is {goal.state.value}{why}, not "
                    f"{wanted.value}; the latest events:\n{self._recent()}"
                )
            time.sleep(POLL)

    # --- the world -----------------------------------------------------------------------

    def facts(self, pattern: str = "") -> list[str]:
        """The true facts and values as text, e.g. ``(robot_at dock)``."""
        reply = planning.STATE_GET.call(self.bus, planning.StateQuery(pattern))
        return [f.text for f in reply.facts]

    def set_fact(self, fact: str, *, at: float | None = None) -> None:
        """Make a fact true (or set a value: ``(= (battery) 80)``), as ``dura state set``;
        with ``at`` (seconds since the epoch), from then on, as ``dura state set --at``."""
        planning.STATE_SET.call(self.bus, planning.FactChange(fact, at=at))

    def unset_fact(self, fact: str, *, at: float | None = None) -> None:
        """Make a fact false, as ``dura state unset`` (``at``: as for :meth:`set_fact`)."""
        planning.STATE_UNSET.call(self.bus, planning.FactChange(fact, at=at))

    def timed_facts(self) -> list[TimedFact]:
        """The facts that take effect later, soonest first, as ``dura state get`` lists
        them under LATER."""
        return planning.STATE_GET.call(self.bus, planning.StateQuery()).timed or []

    # --- events and status ---------------------------------------------------------------

    def events(self, kind: str | None = None, limit: int = 10_000) -> list[Event]:
        """The newest ``limit`` events of the log, oldest first (only events of ``kind``
        if given)."""
        return planning.newest_events(self.bus, limit, kind)

    def wait_for_event(
        self, kind: str, subject: str = "", *, after: int = 0, timeout: float = 60.0
    ) -> Event:
        """Wait for the first event of ``kind`` whose subject contains ``subject``,
        logged after the event numbered ``after``; returns it.

        Raises:
            WaitTimedOut: none within ``timeout`` seconds (with the latest events).
        """
        deadline = time.monotonic() + timeout
        while True:
            query = planning.EventQuery(after=after, limit=10_000, kind=kind, oldest=True)
            reply = planning.EVENTS.call(self.bus, query)
            for event in reply.events:
                if subject in event.subject:
                    return event
            if reply.events:  # none of these: read on after them
                after = reply.events[-1].id
            if reply.more:
                continue
            if time.monotonic() > deadline:
                raise WaitTimedOut(
                    f"no {kind} event{f' about {subject}' if subject else ''} within "
                    f"{timeout:g} s; the latest events:\n{self._recent()}"
                )
            time.sleep(POLL)

    def _recent(self, count: int = 15) -> str:
        return "\n".join(f"  {e.kind} {e.subject} {dict(e.data)}" for e in self.events()[-count:])

    def status(self) -> planning.StatusReply:
        """What ``dura status`` shows."""
        return planning.STATUS.call(self.bus)

    # --- components ----------------------------------------------------------------------

    def components(self) -> list[ComponentEntry]:
        """Every component with its kind, host and state."""
        return COMPONENT_LIST.call(self.bus).components

    def component_state(self, name: str) -> str:
        """A component's state (``ready``, ``stopped``, ...).

        Raises:
            DuraError: the robot has no such component.
        """
        for listed in self.components():
            if listed.component == name:
                return listed.state.value
        raise DuraError(f"robot '{self.robot.name}' has no component '{name}'")

    def wait_for_component(
        self, name: str, state: str = "ready", timeout: float = 60.0
    ) -> ComponentEntry:
        """Wait until the launcher reports a component in ``state`` (``ready``: started
        and configured, so it takes faults and goals); returns it.

        Raises:
            WaitTimedOut: not within ``timeout`` seconds (with its last state and the
                latest events).
            DuraError: the robot has no such component.
        """
        if name not in self.robot.components:
            raise DuraError(f"robot '{self.robot.name}' has no component '{name}'")
        deadline = time.monotonic() + timeout
        while True:
            found = next((c for c in self.components() if c.component == name), None)
            if found is not None and found.state.value == state:
                return found
            if time.monotonic() > deadline:
                now = found.state.value if found is not None else "unknown"
                raise WaitTimedOut(
                    f"component {name} is {now}, not {state}, after {timeout:g} s; the "
                    f"latest events:\n{self._recent()}"
                )
            time.sleep(POLL)

    def inject_fault(
        self, name: str, mode: str, *, timeout: float = INJECT_TIMEOUT, **options: Any
    ) -> None:
        """Make a component misbehave (see :mod:`executive.sdk.fault_injection`) as soon
        as it runs: waits at most ``timeout`` seconds for it to be ready.

        Raises:
            DuraError: it did not run in time, or the executive refused the fault (an
                unknown mode or option: the reason).
        """
        deadline = time.monotonic() + timeout
        while (state := self.component_state(name)) != Lifecycle.READY.value:
            if time.monotonic() > deadline:
                raise DuraError(
                    f"cannot inject {mode!r} into '{name}': it is {state}, not running "
                    f"(waited {timeout:g} s)"
                )
            time.sleep(POLL)
        try:
            COMPONENT_INJECT.call(self.bus, Injection(name, mode, dict(options)))
        except BusError as e:
            raise DuraError(f"cannot inject {mode!r} into '{name}': {e}") from None
