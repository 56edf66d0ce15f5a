"""The dashboard's link to the robot: bus subscriptions in, server-sent events out.

The feed subscribes to the executive's events, diagnoses, observations and component
states, and asks the executive's verbs (:mod:`executive.bus.api`) again only when an
event says their answer changed (a goal event → the goal list, a step event → the
plan, ...), at most every :data:`SETTLE` seconds: the page never polls and neither
does the feed. Everything it learns goes into one :class:`LiveState`, owned by the
event loop the feed runs on; bus callbacks come from Zenoh's threads and are handed to
that loop. Every :data:`FLUSH` seconds the views that changed go to every connected
page as server-sent events.
"""

from __future__ import annotations

import asyncio
import contextlib
import json
import logging
import time
from collections.abc import AsyncIterator, Callable
from typing import Any

from executive.bus.api import components, monitoring, planning, tasks
from executive.bus.keys import DIAGNOSES, EVENTS, EXECUTIVE_ALIVE, OBSERVATIONS, component
from executive.bus.message import Message
from executive.bus.payloads import ComponentState, DiagnosisInfo, read_event
from executive.bus.session import Bus
from executive.dashboard.live import (
    FAULTS,
    GOALS,
    PLAN,
    TASKS,
    VIEWS,
    LiveState,
    event_item,
    stale,
)
from knowledge.errors import DuraError
from knowledge.records import Event
from knowledge.transitions import GoalState, PlanState

log = logging.getLogger("dura.dashboard")

SETTLE = 0.1  # seconds: events that come together make one round of questions
FLUSH = 0.1  # seconds between two pushes of what changed
CLOCK = 1.0  # seconds between two redraws of a running plan's "now"
HISTORY = 500  # events read from the log when the feed starts
RECENT_GOALS = 100  # the goals shown besides the open ones: the newest
OPEN = [s for s in GoalState if s.is_open]
QUEUE = 2000  # messages a page may lag behind before it is dropped (it reconnects)
COMPONENTS, OBSERVATIONS_NOW, EVENTS_NOW, DIAGNOSIS = (
    "components",
    "observations",
    "events",
    "diagnosis",
)
EVERYTHING = (GOALS, PLAN, TASKS, FAULTS, COMPONENTS, OBSERVATIONS_NOW, EVENTS_NOW, DIAGNOSIS)
FLEET = (GOALS, PLAN, EVENTS_NOW)  # a fleet's high level: its robots serve the rest


def sse(name: str, data: Any) -> str:
    """One server-sent event."""
    return f"event: {name}\ndata: {json.dumps(data, separators=(',', ':'), default=str)}\n\n"


class Feed:
    """Keeps a :class:`LiveState` up to date and streams it to pages.

    Args:
        bus: a session with the robot's executive (an operator's).
        state: what the pages are shown.
    """

    def __init__(self, bus: Bus, state: LiveState) -> None:
        self.bus = bus
        self.state = state
        self._loop: asyncio.AbstractEventLoop | None = None
        self._clients: set[asyncio.Queue[str | None]] = set()
        self._stale: set[str] = set()
        self._wake = asyncio.Event()
        self._dirty: set[str] = set()
        self._new_events: list[Event] = []
        self._new_observations: dict[str, dict[str, Any]] = {}
        self._tasks: list[asyncio.Task[None]] = []
        self._subscriptions: list[Any] = []
        self._closed = False

    # --- lifecycle (on the event loop) --------------------------------------------------

    async def start(self) -> None:
        self._loop = asyncio.get_running_loop()
        self._wake = asyncio.Event()
        bus = self.bus
        self._subscriptions = [
            bus.subscribe(EVENTS, self._from_bus(self._on_event)),
            bus.subscribe(DIAGNOSES, self._from_bus(self._on_diagnosis)),
            bus.subscribe(OBSERVATIONS, self._from_bus(self._on_observation)),
            bus.subscribe(component("*", "state"), self._from_bus(self._on_lifecycle)),
            bus.watch_alive(EXECUTIVE_ALIVE, self._on_alive),
        ]
        self._tasks = [
            asyncio.create_task(self._ask_loop(), name="dashboard questions"),
            asyncio.create_task(self._push_loop(), name="dashboard pushes"),
        ]
        self.ask(*EVERYTHING)

    async def stop(self) -> None:
        """End every page's stream and the feed's tasks."""
        self._closed = True
        for subscription in self._subscriptions:
            with contextlib.suppress(Exception):
                subscription.undeclare()
        self._subscriptions = []
        for queue in self._clients:
            queue.put_nowait(None)
        for task in self._tasks:
            task.cancel()
        for task in self._tasks:
            with contextlib.suppress(asyncio.CancelledError):
                await task
        self._tasks = []

    def close_streams(self) -> None:
        """Thread-safe: end every page's stream (the server is stopping)."""
        loop = self._loop
        if loop is not None and not loop.is_closed():
            with contextlib.suppress(RuntimeError):
                loop.call_soon_threadsafe(self._end_streams)

    def _end_streams(self) -> None:
        self._closed = True
        for queue in self._clients:
            queue.put_nowait(None)

    # --- pages --------------------------------------------------------------------------

    async def stream(self) -> AsyncIterator[str]:
        """A page's server-sent events: every view, then what changes, until the page
        goes or the server stops."""
        queue: asyncio.Queue[str | None] = asyncio.Queue()
        now = time.time()
        for name in VIEWS:
            queue.put_nowait(sse(name, self.state.view(name, now)))
        self._clients.add(queue)
        try:
            while not self._closed:
                item = await queue.get()
                if item is None:
                    return
                yield item
        finally:
            self._clients.discard(queue)

    @property
    def clients(self) -> int:
        return len(self._clients)

    def ask(self, *queries: str) -> None:
        """Ask the executive again for these replies (soon, together)."""
        self._stale.update(q for q in queries if not self.state.fleet or q in FLEET)
        self._wake.set()

    def changed(self, *views: str) -> None:
        self._dirty.update(views)

    # --- from the bus (Zenoh's threads → the loop) --------------------------------------

    def _from_bus(self, handler: Callable[[dict[str, Any]], None]) -> Callable[[Message], None]:
        def hand_over(message: Message) -> None:
            loop = self._loop
            if loop is not None and not loop.is_closed():
                with contextlib.suppress(RuntimeError):  # the loop closed meanwhile
                    loop.call_soon_threadsafe(handler, message.payload)

        return hand_over

    def _on_alive(self, key: str, alive: bool) -> None:
        loop = self._loop
        if loop is not None and not loop.is_closed():
            with contextlib.suppress(RuntimeError):
                loop.call_soon_threadsafe(self._set_alive, alive)

    def _set_alive(self, alive: bool) -> None:
        self.state.alive = alive
        self.changed("status")
        if alive:
            self.ask(*EVERYTHING)

    def _on_event(self, payload: dict[str, Any]) -> None:
        event = read_event(payload)
        if event is None or not self.state.add_event(event):
            return
        self._new_events.append(event)
        kind = event.kind
        queries = stale(kind)
        if queries:
            self.ask(*queries)
        if kind in ("FAULT", "COMPONENT_RESET"):
            self.changed("components")
        if PLAN in queries:
            self.changed("plan")

    def _on_diagnosis(self, payload: dict[str, Any]) -> None:
        try:
            diagnosis = DiagnosisInfo.from_payload(payload)
        except (KeyError, TypeError, ValueError):
            log.warning("the dashboard ignored a malformed diagnosis")
            return
        self._set_diagnosis(diagnosis)

    def _set_diagnosis(self, diagnosis: DiagnosisInfo) -> None:
        before = self.state.diagnosis
        self.state.set_diagnosis(diagnosis)
        if _verdict(before) != _verdict(diagnosis):
            self.changed("components")

    def _on_observation(self, payload: dict[str, Any]) -> None:
        track = self.state.add_observation(payload)
        self._new_observations[track.key] = {**track.item(), "point": list(track.history[-1])}

    def _on_lifecycle(self, payload: dict[str, Any]) -> None:
        try:
            state = ComponentState.from_payload(payload)
        except (KeyError, TypeError, ValueError):
            log.warning("the dashboard ignored a malformed component state")
            return
        self.state.set_lifecycle(state)
        self.changed("components")

    # --- asking the executive ----------------------------------------------------------

    async def _ask_loop(self) -> None:
        while True:
            await self._wake.wait()
            await asyncio.sleep(SETTLE)
            self._wake.clear()
            todo, self._stale = self._stale, set()
            problems = []
            for query in [q for q in EVERYTHING if q in todo]:
                try:
                    answer = await asyncio.to_thread(self._fetch, query)
                    self._apply(query, answer)
                except DuraError as e:
                    problems.append(str(e))
                except Exception:  # a reply of an unexpected shape must not stop the feed
                    log.exception("the dashboard could not take the answer to '%s'", query)
            problem = problems[0] if problems else ""
            if problem != self.state.problem:
                self.state.problem = problem
                self.changed("status")

    def _fetch(self, query: str) -> Any:
        """Ask the executive (blocking: on a worker thread); the answer for :meth:`_apply`."""
        bus = self.bus
        if query == GOALS:  # not all: a long run's goals are many
            open_goals = planning.GOAL_LIST.call(bus, planning.GoalQuery(OPEN)).goals
            recent = planning.GOAL_LIST.call(bus, planning.GoalQuery(limit=RECENT_GOALS)).goals
            return sorted({g.id: g for g in [*open_goals, *recent]}.values(), key=lambda g: g.id)
        if query == PLAN:
            return planning.PLAN_SHOW.call(bus)
        if query == TASKS:
            return tasks.TASK_LIST.call(bus).tasks
        if query == FAULTS:
            return planning.STATUS.call(bus).faults, tasks.SCHEDULE_SHOW.call(bus).faulty
        if query == COMPONENTS:
            return components.COMPONENT_LIST.call(bus).components
        if query == OBSERVATIONS_NOW:
            return monitoring.OBSERVER_LATEST.call(bus).observations
        if query == EVENTS_NOW:
            return planning.newest_events(bus, HISTORY)
        if query == DIAGNOSIS:
            return planning.STATUS.call(bus).diagnosis
        raise ValueError(query)

    def _apply(self, query: str, answer: Any) -> None:
        """Take an answer into the state (on the loop: only the loop changes it)."""
        state = self.state
        if query == GOALS:
            state.set_goals(answer)
            self.changed("goals")
        elif query == PLAN:
            state.set_plan(answer.plan, answer.execution, answer.robots)
            self.changed("plan")
        elif query == TASKS:
            state.set_tasks(answer)
            self.changed("plan", "components")
        elif query == FAULTS:
            state.set_faults(*answer)
            self.changed("components")
        elif query == COMPONENTS:
            state.set_components(answer)
            self.changed("components")
        elif query == OBSERVATIONS_NOW:
            for payload in answer:
                state.add_observation(payload)
            self.changed("observations")
        elif query == EVENTS_NOW:
            state.set_events(answer)
            self.changed("events", "plan")
        elif query == DIAGNOSIS and state.diagnosis is None and answer is not None:
            self._set_diagnosis(answer)  # a live one is newer

    # --- pushing to pages ---------------------------------------------------------------

    async def _push_loop(self) -> None:
        last_clock = 0.0
        while True:
            await asyncio.sleep(FLUSH)
            now = time.time()
            plan = self.state.plan
            if plan is not None and plan.state is PlanState.EXECUTING and now - last_clock > CLOCK:
                self._dirty.add("plan")
                last_clock = now
            messages = []
            for name in [v for v in VIEWS if v in self._dirty]:
                try:
                    messages.append(sse(name, self.state.view(name, now)))
                except Exception:  # one view that cannot be drawn must not stop the others
                    log.exception("the dashboard could not draw its '%s' view", name)
            self._dirty.clear()
            if self._new_events:
                items = [event_item(e) for e in self._new_events]
                messages.append(sse("event", {"events": items}))
                self._new_events = []
            if self._new_observations:
                items = list(self._new_observations.values())
                messages.append(sse("observation", {"observations": items, "now": now}))
                self._new_observations = {}
            if messages:
                self._send("".join(messages))

    def _send(self, text: str) -> None:
        for queue in list(self._clients):
            if queue.qsize() > QUEUE:
                log.warning("a dashboard page lags %d messages behind: dropped", QUEUE)
                self._clients.discard(queue)
                queue.put_nowait(None)
            else:
                queue.put_nowait(text)


def _verdict(diagnosis: DiagnosisInfo | None) -> tuple[str, str]:
    """What the picture shows of a diagnosis (a repeated one changes nothing)."""
    if diagnosis is None:
        return "None", "[null, null]"
    return diagnosis.status, json.dumps([diagnosis.diagnoses, diagnosis.failed], sort_keys=True)
