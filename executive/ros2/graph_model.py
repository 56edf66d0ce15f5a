"""The diagnosis model's ROS 2 nodes: their topics come from ROS 2 discovery.

A component that is a ROS 2 program (``ros2: {node: ...}``) need not list the topics
it publishes and subscribes: while it runs, the diagnosis model's node of that
component gets the topics ROS 2 discovery says its node has (plus those the
description lists), as observers name them (``/scan`` is ``scan``). Hidden topics
(a token starting with ``_``, e.g. an action's feedback) and every node's
``/rosout`` and ``/parameter_events`` are left out.

The task executor adds a component's node to the model when the component is ready
and removes it when it stops; this service then brings the node's topics in line
with the graph, and again whenever the graph changes: it reads the model (GET) and
replaces a node whose topics differ (UPDATE). A node not yet in the model is tried
again a little later, for a while (a component started by hand, not by a task, is not
in the model). Everything runs on one thread of its own.
"""

from __future__ import annotations

import logging
import threading
from collections.abc import Mapping
from typing import Any

from executive.bus.api.monitoring import DIAGNOSIS_MODEL_CHANGE, ModelChange
from executive.bus.keys import component
from executive.bus.message import Message
from executive.bus.payloads import ComponentState
from executive.bus.service import Context, Service
from executive.bus.states import Lifecycle
from executive.ros2.discovery import Discovery
from knowledge.errors import DuraError

log = logging.getLogger("dura.ros2")

SETTLE = 0.2  # seconds to gather changes of the graph before the model follows
RETRY = 0.5  # seconds before trying again for a node the model does not have yet
TRIES = 20  # tries for one node (a component started by hand is never in the model)
ANSWER = 2.0  # seconds the diagnosis engine gets to answer


def observed(topics: tuple[str, ...]) -> list[str]:
    """Name ROS 2 topics as observers do, without hidden topics: ``/scan`` -> ``scan``."""
    return [t.strip("/") for t in topics if not any(p.startswith("_") for p in t.split("/"))]


class Ros2GraphModel(Service):
    """Keeps the diagnosis model's ROS 2 nodes' topics in line with ROS 2 discovery.

    Args:
        context: the robot (which components are ROS 2 nodes) and the bus.
        discovery: the executive's view of the ROS 2 graph.
    """

    name = "ros2-graph-model"

    def __init__(self, context: Context, discovery: Discovery) -> None:
        super().__init__(context)
        self.discovery = discovery
        robot = context.robot
        self.nodes: Mapping[str, str] = {
            name: spec.ros2.node
            for name, spec in robot.components.items()
            if spec.ros2 is not None and spec.ros2.node is not None
        }
        self._changed = threading.Condition()
        self._dirty = False
        self._running = False
        self._ready: set[str] = set()
        self._tries: dict[str, int] = {}  # of nodes not in the model yet
        self._thread: threading.Thread | None = None
        self._subscription: Any = None

    def on_activate(self) -> None:
        if not self.nodes:
            return
        self._running = True
        self._thread = threading.Thread(target=self._loop, name="ros2-graph-model", daemon=True)
        self._thread.start()
        self._subscription = self.context.bus.subscribe(component("*", "state"), self._on_state)
        self.discovery.on_change(self._mark)

    def on_deactivate(self) -> None:
        if self._subscription is not None:
            try:
                self._subscription.undeclare()
            except Exception as e:  # already closed with the bus
                log.debug("undeclare: %s", e)
            self._subscription = None
        with self._changed:
            self._running = False
            self._changed.notify_all()
        if self._thread is not None:
            self._thread.join()
            self._thread = None

    def topics(self, name: str) -> tuple[list[str], list[str]]:
        """Return what a component's node subscribes and publishes: description and graph."""
        spec = self.context.robot.components[name]
        found = self.discovery.nodes().get(self.nodes[name])
        subs = {*spec.subscribes, *(observed(found.subscribes) if found else [])}
        pubs = {*spec.publishes, *(observed(found.publishes) if found else [])}
        return sorted(subs), sorted(pubs)

    # --- changes ------------------------------------------------------------------------

    def _on_state(self, message: Message) -> None:
        try:
            state = ComponentState.from_payload(message.payload)
        except (KeyError, ValueError, TypeError):
            return
        if state.component not in self.nodes:
            return
        with self._changed:
            if state.state is Lifecycle.READY:
                self._ready.add(state.component)
            else:
                self._ready.discard(state.component)
            self._tries.pop(state.component, None)
            self._dirty = True
            self._changed.notify_all()

    def _mark(self) -> None:
        with self._changed:
            self._dirty = True
            self._changed.notify_all()

    def _loop(self) -> None:
        while True:
            with self._changed:
                self._changed.wait_for(lambda: self._dirty or not self._running)
                if not self._running:
                    return
                self._changed.wait_for(lambda: not self._running, SETTLE)  # gather more
                self._dirty = False
                ready = sorted(n for n in self._ready if self._tries.get(n, 0) < TRIES)
            missing = self._sync(ready) if ready else set()
            if missing:
                with self._changed:
                    for name in missing:
                        self._tries[name] = self._tries.get(name, 0) + 1
                    self._changed.wait_for(lambda: not self._running, RETRY)
                    self._dirty = True

    def _sync(self, ready: list[str]) -> set[str]:
        """Update the model's nodes of these components; those the model lacks (or all of
        them, if the model could not be changed)."""
        bus = self.context.bus
        try:
            reply = DIAGNOSIS_MODEL_CHANGE.call(bus, ModelChange("GET"), timeout=ANSWER)
        except DuraError as e:
            log.warning("cannot read the diagnosis model: %s", e)
            return set(ready)
        model = {str(n["name"]): n for n in (reply.model or {}).get("nodes", [])}
        missing = set()
        changed: list[dict[str, Any]] = []
        for name in ready:
            node = model.get(name)
            if node is None:
                missing.add(name)  # the task executor adds it when it is ready
                continue
            with self._changed:
                self._tries.pop(name, None)
            subs, pubs = self.topics(name)
            if (
                sorted(node.get("sub_topic", [])) != subs
                or sorted(node.get("pub_topic", [])) != pubs
            ):
                changed.append({"name": name, "sub_topic": subs, "pub_topic": pubs})
        if changed:
            try:
                answer = DIAGNOSIS_MODEL_CHANGE.call(
                    bus, ModelChange("UPDATE", nodes=changed), timeout=ANSWER
                )
            except DuraError as e:
                log.warning("diagnosis model not updated from the ROS 2 graph: %s", e)
                return set(ready)
            if not answer.ok:
                log.warning("diagnosis model refused the ROS 2 graph's topics: %s", answer.error)
                return set(ready)
            names = ", ".join(str(n["name"]) for n in changed)
            log.info("diagnosis model: topics of %s from the ROS 2 graph", names)
        return missing
