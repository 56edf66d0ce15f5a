"""The record of component states: published, logged in the KB, told to listeners.

Every state a component goes through is published at once on ``component/<name>/state``
(by the thread that changed it, so the bus sees the states in their order). One thread
of its own then logs it in the KB event log and calls the listeners, one after the
other and in the same order: a slow listener or KB write never holds up a start or a
stop.
"""

from __future__ import annotations

import logging
import queue
import threading
from collections.abc import Callable
from typing import Any

from executive.bus import keys
from executive.bus.payloads import ComponentState
from executive.bus.session import Bus
from knowledge.errors import DuraError
from knowledge.knowledge_base import KnowledgeBase

log = logging.getLogger("dura.launcher")

Listener = Callable[[ComponentState], None]


def call_safely(fn: Callable[[Any], None], arg: Any) -> None:
    """Call a listener or callback; what it raises is logged, not passed on."""
    try:
        fn(arg)
    except Exception:
        log.exception("callback %r failed", fn)


class StateRecords:
    """Publishes, logs and tells every new component state, in order."""

    def __init__(self, bus: Bus, kb: KnowledgeBase) -> None:
        self.bus = bus
        self.kb = kb
        self._lock = threading.Lock()
        self._listeners: list[Listener] = []
        self._notices: queue.SimpleQueue[ComponentState | None] = queue.SimpleQueue()
        self._thread = threading.Thread(target=self._notify, name="launcher-notices", daemon=True)

    def open(self) -> None:
        self._thread.start()

    def close(self) -> None:
        """Tell what is left, then end the thread."""
        self._notices.put(None)
        self._thread.join()

    def add_listener(self, listener: Listener) -> None:
        with self._lock:
            self._listeners.append(listener)

    def remove_listener(self, listener: Listener) -> None:
        with self._lock:
            self._listeners.remove(listener)

    def record(self, state: ComponentState) -> None:
        """Publish a new state now; log it and tell the listeners soon.

        Callers record a component's states one at a time (under their lock), so that
        they are published and told in the order they happened.
        """
        try:
            self.bus.publish(keys.component(state.component, "state"), state.to_payload())
        except DuraError as e:
            log.warning("cannot publish the state of '%s': %s", state.component, e)
        self._notices.put(state)

    def _notify(self) -> None:
        while (state := self._notices.get()) is not None:
            payload = state.to_payload()
            del payload["component"], payload["state"]
            try:
                self.kb.log_event(f"COMPONENT_{state.state.name}", state.component, payload)
            except DuraError as e:
                log.warning("cannot log the state of '%s': %s", state.component, e)
            with self._lock:
                listeners = list(self._listeners)
            for listener in listeners:
                call_safely(listener, state)
