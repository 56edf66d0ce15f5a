"""The observer manager (thesis 5.2.2, 6.2.2): runs every observer, changeable at run time.

It loads the observers of every component of the robot description (ids
``<component>/<index>``) and, unlike the thesis' manager, lets observers be added,
changed, removed, activated and deactivated while it runs, through its methods or
its bus API (:func:`executive.bus.keys.observers_api`).

An observer observes (is *active*) while it is enabled
(:meth:`ObserverManager.activate_observer`, the default) and its component's last state from the launcher
(``component/<name>/state``) is READY; an observer without a component only needs to
be enabled. So a stopped, paused or crashed component never produces fault reports,
and an observer starts afresh (start-up time, empty filters) each time it becomes
active.

Every bus key an observer listens to has one subscription, shared by all observers
of that key. A key that a topic source serves (a ROS 2
topic: :mod:`executive.bus.topic_source`) is subscribed there instead of on the bus. One loop thread runs each active observer at its
rate and publishes each result on ``observations``.

The loop itself takes a bus key's messages from its subscription's queue
(:meth:`executive.bus.session.Bus.poll`) before each round, and at least every
``TAKE_EVERY`` seconds: a message that has reached the executive is always seen by the
next round, however busy the process is. A handler thread of its own could be left
waiting while the loop runs, and the observers would count that wait as the
publisher's silence (a false timeout under CPU load). A message's ``received`` time is
when it arrived: when the executive's Python first saw it, as a recorder stamps it, or
for one the loop took before that, its send stamp moved onto the executive's clock, at
most when the loop took it (see :meth:`~executive.bus.session.Bus.poll`). So a
silence is the publisher's and the network's, never the executive's own lateness, and
no time depends on when the loop takes.
"""

from __future__ import annotations

import logging
import threading
import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

from executive.bus.api.monitoring import ObserverStatus
from executive.bus.clock import Clock, system_clock
from executive.bus.keys import OBSERVATIONS, component
from executive.bus.message import Message
from executive.bus.payloads import ComponentState
from executive.bus.polled import Polled
from executive.bus.service import Context, Service
from executive.bus.states import Lifecycle
from executive.bus.topic_source import TopicSource
from knowledge.description import ObserverSpec
from knowledge.errors import ConfigError, DuraError, did_you_mean
from monitoring.observer import Environment, Handler, Observer, make_observer
from monitoring.observer_api import serve_observers
from monitoring.observer_config import config_of
from monitoring.robot_time import RobotTime

log = logging.getLogger("dura.observers")

TAKE_EVERY = 0.1  # wall seconds: the loop takes the queued messages at least this often

ObserverEntry = ObserverSpec | Mapping[str, Any]


@dataclass
class _Slot:
    id: str
    component: str | None
    observer: Observer
    inputs: list[tuple[str, Handler]]
    enabled: bool = True
    active: bool = False
    due: float = 0.0  # monotonic time of its next loop

    def status(self) -> ObserverStatus:
        config = self.observer.config
        return ObserverStatus(
            self.id,
            config.type,
            self.component,
            self.enabled,
            self.active,
            1.0 / self.observer.period,
            config.start_up_time,
        )


@dataclass
class _Feed:
    """One bus subscription and the handlers of the active observers of its key."""

    subscriber: Any = None
    handlers: tuple[Handler, ...] = ()
    users: dict[int, _Slot] = field(default_factory=dict)  # the observers on it, by identity
    queue: Polled | None = None  # a bus key's messages, until the loop takes them
    receive: Handler | None = None  # deliver, on the robot-time axis

    def take(self) -> None:
        """Deliver the queued messages (on the loop's thread)."""
        if self.queue is not None and self.receive is not None:
            for message in self.queue.drain():
                self.receive(message)

    def deliver(self, message: Message) -> None:
        for handler in self.handlers:
            try:
                handler(message)
            except Exception:
                log.exception("observer handler for %s failed", message.key)


class ObserverManager(Service):
    """Runs the observers of a robot; see the module documentation."""

    name = "observer-manager"

    def __init__(
        self, context: Context, *, sources: Sequence[TopicSource] = (), clock: Clock | None = None
    ) -> None:
        super().__init__(context)
        self._time = RobotTime(clock or system_clock())  # observers measure robot time
        self._sources = tuple(sources)  # topics not on the bus, e.g. ROS 2 topics
        self._lock = threading.Condition(threading.RLock())
        self._slots: dict[str, _Slot] = {}
        self._feeds: dict[str, _Feed] = {}
        self._states: dict[str, Lifecycle] = {}
        self._latest: dict[tuple[str, str, tuple[str, ...], tuple[str, ...]], dict[str, Any]] = {}
        self._declared: list[Any] = []
        self._thread: threading.Thread | None = None
        self._stopping = True  # observers observe only while the manager is active

    # --- lifecycle ------------------------------------------------------------------

    def on_configure(self) -> None:
        """Load the robot's observers (they observe once active).

        Raises:
            ConfigError: an observer of the robot description is invalid.
        """
        robot = self.context.robot
        observers = [
            (f"{c.name}/{i}", c.name, self._observer(spec, c.name, str(robot.path)))
            for c in robot.components.values()
            for i, spec in enumerate(c.observers)
        ]
        with self._lock:
            for observer_id, owner, observer in observers:
                self._register(_Slot(observer_id, owner, observer, observer.inputs()))

    def on_activate(self) -> None:
        """Listen to component states, serve the API, loop."""
        with self._lock:
            self._stopping = False
            for slot in self._slots.values():
                self._refresh(slot)
        bus = self.context.bus
        self._declared.append(bus.subscribe(component("*", "state"), self._on_component_state))
        self._declared.extend(serve_observers(self, bus))
        self._thread = threading.Thread(target=self._run, name="observer-manager", daemon=True)
        self._thread.start()

    def on_deactivate(self) -> None:
        with self._lock:
            self._stopping = True
            self._lock.notify_all()
        if self._thread is not None:
            self._thread.join()
            self._thread = None
        with self._lock:
            entities, self._declared = self._declared, []
            for slot in self._slots.values():
                self._refresh(slot)  # stopping: none observes
        _undeclare(entities)

    def on_shutdown(self) -> None:
        with self._lock:
            entities = [f.subscriber for f in self._feeds.values()]
            self._feeds.clear()
        _undeclare(entities)

    # --- the Python API -------------------------------------------------------------

    def add(
        self,
        config: ObserverEntry,
        *,
        component: str | None = None,
        name: str | None = None,
        source: str = "observer",
    ) -> str:
        """Add an observer (of ``component``, or of its own); returns its id.

        ``source`` names where the configuration came from in error messages (a file).

        Raises:
            ConfigError: the configuration is invalid, the component unknown or the
                name taken.
        """
        with self._lock:
            return self._add(config, component, name, source)

    def active(self, observer_id: str) -> bool:
        """Whether an observer observes now (enabled, and its component READY).

        Raises:
            ConfigError: unknown id.
        """
        with self._lock:
            return self._slot(observer_id).active

    def change(self, observer_id: str, config: ObserverEntry, *, source: str = "observer") -> None:
        """Replace an observer's configuration; it keeps its id and starts afresh.

        Raises:
            ConfigError: unknown id or invalid configuration (the old one stays).
        """
        with self._lock:
            slot = self._slot(observer_id)
            observer = self._observer(config, slot.component, source)
            inputs = observer.inputs()
            self._register(_Slot(observer_id, slot.component, observer, inputs, slot.enabled))
            self._unregister(slot)  # after: a subscription both need stays declared

    def remove(self, observer_id: str) -> None:
        """Remove an observer.

        Raises:
            ConfigError: unknown id.
        """
        with self._lock:
            self._unregister(self._slot(observer_id))

    def activate_observer(self, observer_id: str) -> bool:
        """Enable an observer; returns whether it observes now (its component is READY)."""
        with self._lock:
            slot = self._slot(observer_id)
            slot.enabled = True
            self._refresh(slot)
            return slot.active

    def deactivate_observer(self, observer_id: str) -> None:
        """Disable an observer until it is activated again."""
        with self._lock:
            slot = self._slot(observer_id)
            slot.enabled = False
            self._refresh(slot)

    def component_changed(self, state: ComponentState) -> None:
        """Take note of a component's lifecycle state (what the launcher reports)."""
        with self._lock:
            self._states[state.component] = state.state
            for slot in list(self._slots.values()):
                if slot.component == state.component:
                    self._refresh(slot)

    def observers(self) -> list[ObserverStatus]:
        with self._lock:
            return [slot.status() for slot in self._slots.values()]

    def subscriptions(self) -> dict[str, int]:
        """Every bus key the manager subscribes to, with how many observers share it."""
        with self._lock:
            return {key: len(feed.users) for key, feed in self._feeds.items()}

    def latest(self) -> list[dict[str, Any]]:
        """The last observation of every resource of every active observer (payloads)."""
        with self._lock:
            return list(self._latest.values())

    # --- registration ---------------------------------------------------------------

    def _slot(self, observer_id: str) -> _Slot:
        slot = self._slots.get(observer_id)
        if slot is None:
            hint = did_you_mean(observer_id, sorted(self._slots))
            raise ConfigError(f"no observer '{observer_id}'{hint}")
        return slot

    def _observer(self, config: ObserverEntry, owner: str | None, path: str) -> Observer:
        robot = self.context.robot
        if owner is not None and owner not in robot.components:
            hint = did_you_mean(owner, sorted(robot.components))
            raise ConfigError(f"{path}: no component '{owner}' in robot '{robot.name}'{hint}")
        where = f"{robot.components[owner].kind.value} '{owner}'" if owner else ""
        environment = Environment(
            owner=owner,
            behavior=owner if owner in robot.behaviors else None,
            component_state=self._states.get,
        )
        return make_observer(config_of(config, path=path, owner=where), environment)

    def _add(self, config: ObserverEntry, owner: str | None, name: str | None, path: str) -> str:
        if name is not None and (not name or name in self._slots):
            raise ConfigError(f"{path}: observer name '{name}' is {'taken' if name else 'empty'}")
        observer = self._observer(config, owner, path)
        if name is None:
            prefix = owner or "observer"
            number = sum(1 for s in self._slots if s.startswith(prefix + "/"))
            while f"{prefix}/{number}" in self._slots:
                number += 1
            name = f"{prefix}/{number}"
        self._register(_Slot(name, owner, observer, observer.inputs()))
        return name

    def _register(self, slot: _Slot) -> None:
        self._slots[slot.id] = slot
        for key, _ in slot.inputs:
            feed = self._feeds.get(key)
            if feed is None:
                feed = self._feeds[key] = _Feed()
                source = next((s for s in self._sources if s.serves(key)), None)
                feed.receive = self._time.handler(feed.deliver)
                if source is not None:
                    feed.subscriber = source.subscribe(key, feed.receive)
                else:  # taken by the loop: see the module documentation
                    feed.subscriber = feed.queue = self.context.bus.poll(key)
            feed.users[id(slot)] = slot
        self._refresh(slot)

    def _unregister(self, slot: _Slot) -> None:
        slot.enabled = False
        self._refresh(slot)
        if self._slots.get(slot.id) is slot:
            del self._slots[slot.id]
        for key, _ in slot.inputs:
            feed = self._feeds.get(key)
            if feed is None:
                continue
            feed.users.pop(id(slot), None)
            if not feed.users:
                del self._feeds[key]
                try:
                    feed.subscriber.undeclare()
                except Exception as e:
                    log.debug("undeclare %s: %s", key, e)

    def _refresh(self, slot: _Slot) -> None:
        """(De)activate an observer as its flag and its component's state say."""
        ready = slot.component is None or self._states.get(slot.component) is Lifecycle.READY
        should = slot.enabled and ready and not self._stopping
        if should == slot.active:
            return
        slot.active = should
        for key, handler in slot.inputs:
            feed = self._feeds[key]
            feed.take()  # what came before is not the activated observer's
            if should:
                feed.handlers = (*feed.handlers, handler)
            else:
                feed.handlers = tuple(h for h in feed.handlers if h is not handler)
        if should:
            slot.observer.start_ns(self._time.now_ns())
            slot.due = time.monotonic() + self._time.clock.wall(slot.observer.first_report)
            self._lock.notify_all()
        else:
            for old in [k for k in self._latest if k[0] == slot.id]:
                del self._latest[old]

    def _on_component_state(self, message: Message) -> None:
        try:
            state = ComponentState.from_payload(message.payload)
        except (KeyError, ValueError, TypeError) as e:
            log.warning("malformed component state on %s: %s", message.key, e)
            return
        self.component_changed(state)

    # --- the loop -------------------------------------------------------------------

    def _run(self) -> None:
        while True:
            with self._lock:
                if self._stopping:
                    return
                now = time.monotonic()
                active = [s for s in self._slots.values() if s.active]
                due = [s for s in active if s.due <= now]
                if not due:
                    self._take()  # the queues stay short between loops
                    wait = min((s.due for s in active), default=now + 3600.0) - now
                    self._lock.wait(min(wait, TAKE_EVERY))
                    continue
                payloads = self._observe(due, now)
            for payload in payloads:
                try:
                    self.context.bus.publish(OBSERVATIONS, payload)
                except DuraError as e:
                    log.warning("cannot publish an observation: %s", e)

    def _take(self) -> None:
        """Deliver every feed's queued messages (on the loop's thread)."""
        for feed in self._feeds.values():
            feed.take()

    def _observe(self, due: list[_Slot], now: float) -> list[dict[str, Any]]:
        self._take()  # all that arrived before now, handled or not
        wall, robot_now = time.time(), self._time.now_ns()
        payloads: list[dict[str, Any]] = []
        for slot in due:
            period = self._time.clock.wall(slot.observer.period)
            slot.due = slot.due + period if slot.due + period > now else now + period
            try:
                results = slot.observer.observe_ns(robot_now)
            except Exception:
                log.exception("observer %s failed", slot.id)
                continue
            for result in results:
                info = result.info
                payload = {**result.to_payload(slot.id), "stamp": wall}
                self._latest[(slot.id, info.type, info.resource, info.callerids)] = payload
                payloads.append(payload)
        return payloads


def _undeclare(entities: list[Any]) -> None:
    for entity in entities:
        try:
            entity.undeclare()
        except Exception as e:  # already closed with the bus
            log.debug("undeclare: %s", e)
