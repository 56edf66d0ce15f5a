"""Facts that take effect later ("the door opens at 14:00"): the knowledge base keeps
them (:class:`~knowledge.records.TimedFact`, a wall-clock time each), the planner plans
with those to come as timed initial literals
(:func:`executive.planning.problem.live_world`), and :class:`TimedFacts` makes each a
fact of the world when its time comes, as a sensing rule would (a ``STATE_SET`` or
``STATE_UNSET`` event by ``timed``), so that the plan ahead is checked and the goal
planner wakes.
"""

from __future__ import annotations

import logging
import threading
import time
from collections.abc import Callable

from knowledge.knowledge_base import KnowledgeBase
from knowledge.records import Fact

log = logging.getLogger("dura.timed_facts")

SOURCE = "timed"  # who changes the facts, as the event log records it


class TimedFacts:
    """Applies the knowledge base's timed facts when they are due, on a thread of its own.

    Args:
        kb: the knowledge base (its timed facts).
        changed: told of the facts that took effect, with a reason.
    """

    def __init__(self, kb: KnowledgeBase, changed: Callable[[list[Fact], str], None]) -> None:
        self.kb = kb
        self.changed = changed
        self._wake = threading.Event()
        self._stopping = threading.Event()
        self._thread = threading.Thread(target=self._run, name="timed-facts", daemon=True)

    def start(self) -> None:
        self._thread.start()

    def stop(self) -> None:
        self._stopping.set()
        self._wake.set()
        if self._thread.ident is not None:
            self._thread.join()

    def added(self) -> None:
        """A timed fact was added: look at the next due time again."""
        self._wake.set()

    def apply_due(self) -> list[Fact]:
        """Make the facts due by now facts of the world (one transaction, an event each)."""
        with self.kb.transaction():
            due = self.kb.apply_due_facts(time.time())
            for t in due:
                kind = "STATE_UNSET" if t.fact.value is False else "STATE_SET"
                self.kb.log_event(kind, str(t.fact), {"source": SOURCE, "at": t.at})
        facts = [t.fact for t in due]
        if facts:
            shown = ", ".join(str(f) for f in facts)
            self.changed(facts, f"{shown} took effect at {time.strftime('%H:%M:%S')}")
        return facts

    def _run(self) -> None:
        while not self._stopping.is_set():
            try:
                self.apply_due()
                upcoming = self.kb.timed_facts()
            except Exception:  # a failed look must not end the thread
                log.exception("applying timed facts failed")
                upcoming = []
            wait = None if not upcoming else max(0.0, upcoming[0].at - time.time())
            self._wake.wait(wait)
            self._wake.clear()
