"""A managed node as rcl_lifecycle runs one: its states, transitions and services."""

from __future__ import annotations

import threading
import time
from typing import Any

from . import interfaces as ros
from .rosnode import Node

PRIMARY = {1: "unconfigured", 2: "inactive", 3: "active", 4: "finalized"}
# transition id: (label, start state, intermediate state, goal state, callback name)
TRANSITIONS = {
    1: ("configure", 1, 10, 2, "on_configure"),
    2: ("cleanup", 2, 11, 1, "on_cleanup"),
    3: ("activate", 2, 13, 3, "on_activate"),
    4: ("deactivate", 3, 14, 2, "on_deactivate"),
    5: ("shutdown", 1, 12, 4, "on_shutdown"),
    6: ("shutdown", 2, 12, 4, "on_shutdown"),
    7: ("shutdown", 3, 12, 4, "on_shutdown"),
}
LABELS = {1: "unconfigured", 2: "inactive", 3: "active", 4: "finalized", 10: "configuring",
          11: "cleaningup", 12: "shuttingdown", 13: "activating", 14: "deactivating"}  # fmt: skip


class LifecycleNode(Node):
    """A managed node: override ``on_configure`` ... ``on_shutdown`` (return success)."""

    def __init__(self, name: str, namespace: str = "/", domain_id: int | None = None) -> None:
        super().__init__(name, namespace, domain_id)
        self.state = 1
        self._changing = threading.Lock()
        base = self.full_name
        self._events = self.publisher(base + "/transition_event", ros.TransitionEvent)
        self.service(base + "/get_state", ros.GetState_Request, ros.GetState_Response, self._get)
        self.service(
            base + "/change_state", ros.ChangeState_Request, ros.ChangeState_Response, self._change
        )

    def on_configure(self) -> bool:
        return True

    def on_activate(self) -> bool:
        return True

    def on_deactivate(self) -> bool:
        return True

    def on_cleanup(self) -> bool:
        return True

    def on_shutdown(self) -> bool:
        return True

    @property
    def active(self) -> bool:
        return self.state == 3

    def _get(self, request: Any) -> dict[str, Any]:
        return {"current_state": ros.State(id=self.state, label=LABELS[self.state])}

    def _event(self, label: str, tid: int, start: int, goal: int) -> None:
        self._events.write(ros.TransitionEvent(
            timestamp=time.time_ns(), transition=ros.Transition(id=tid, label=label),
            start_state=ros.State(id=start, label=LABELS[start]),
            goal_state=ros.State(id=goal, label=LABELS[goal]),
        ))  # fmt: skip

    def _change(self, request: Any) -> dict[str, Any]:
        with self._changing:
            found = TRANSITIONS.get(request.transition.id)
            if found is None or found[1] != self.state:
                return {"success": False}  # not a transition from this state
            label, start, middle, goal, callback = found
            self.state = middle
            self._event(label, request.transition.id, start, middle)
            ok = bool(getattr(self, callback)())
            self.state = goal if ok else start
            self._event("transition_success" if ok else "transition_failure",
                        97 if ok else 98, middle, self.state)  # fmt: skip
            return {"success": ok}
