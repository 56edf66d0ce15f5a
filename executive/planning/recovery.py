"""Recovery after a crash: take back what the dead executive's unfinished steps did.

A step's at-start effects and its START event are written in one transaction, with
what each changed fact was before (``undo``). When the executive died with steps under
way, nobody knows how far they got; as far as the executive can tell, the world is as it
was before them, and the goal planner plans from there (components that know better
write facts).
"""

from __future__ import annotations

from typing import Any

from knowledge.knowledge_base import KnowledgeBase
from knowledge.records import Fact


def recover(kb: KnowledgeBase) -> list[str]:
    """After the executive died: take back the at-start effects of the steps it had
    started and not ended (recorded with their START events); returns their labels.

    Call before planning again, when the current run's EXECUTIVE_STARTED is logged.
    """
    runs = [e.id for e in kb.events(kind="EXECUTIVE_STARTED")]
    if len(runs) < 2:
        return []
    unfinished: dict[tuple[Any, Any], Any] = {}
    for e in kb.events(after=runs[-2] - 1):
        if e.id >= runs[-1]:
            break
        key = (e.data.get("plan"), e.data.get("step"))
        if e.kind == "START":
            unfinished[key] = e
        elif e.kind in ("END", "FAIL", "CANCEL"):
            unfinished.pop(key, None)
    labels = []
    for e in unfinished.values():
        undo = e.data.get("undo") or []
        with kb.transaction():
            kb.update_facts(
                add=[Fact(n, tuple(a), v) for n, a, v in undo if v is not None],
                remove=[Fact(n, tuple(a)) for n, a, v in undo if v is None],
            )
            kb.log_event("CANCEL", e.subject, {**e.data, "reason": "the executive died"})
        labels.append(e.subject)
    return labels
