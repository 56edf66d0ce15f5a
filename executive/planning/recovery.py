"""Recovery after a crash: take back what the dead executive's unfinished steps did.

Every change a step makes to the facts is written in one transaction with its event:
its at-start effects with START (and what each changed fact was before, ``undo``), its
at-end effects with END, the undo of its at-start effects with FAIL or CANCEL. Each
event names the step's run (the id of the DISPATCH event that began it), which stays
the same when a later plan continues the run (ADOPT); so a run without an END, FAIL or
CANCEL is a step that was under way when the executive died, whatever plans replaced
each other meanwhile. Recovery ends each with a CANCEL (and marks its plan step
cancelled); one that had started is taken back: nobody knows how far it got, so as far
as the executive can tell, the world is as it was before it, and the goal planner plans
from there (components that know better write facts).

A recovery ends with a ``RECOVERED`` event: every run started before it has ended. The
next recovery reads the step events after it, so one that was itself killed half-way
is finished by the next executive, and none is done twice.
"""

from __future__ import annotations

import contextlib
from collections.abc import Hashable
from dataclasses import dataclass

from knowledge.errors import KnowledgeError
from knowledge.knowledge_base import KnowledgeBase
from knowledge.records import Event, Fact

RECOVERED = "RECOVERED"  # the event that closes a recovery
STEP_EVENTS = ("DISPATCH", "START", "ADOPT", "END", "FAIL", "CANCEL")
DIED = "the executive died"


@dataclass
class _Run:
    """A step run as the log tells it: the event that began it (DISPATCH, or START in a
    log written before runs were named), its START, and the plan step it is now."""

    began: Event
    start: Event | None = None
    holder: tuple[object, object] = (None, None)


def recover(kb: KnowledgeBase) -> list[str]:
    """End the step runs a dead executive left under way: take back the at-start effects
    of those that started; returns their labels, oldest first.

    Call it when the executive starts, before it executes anything.
    """
    marks = kb.events(kind=RECOVERED, limit=1)
    events = kb.events(after=marks[-1].id if marks else 0, kinds=STEP_EVENTS)
    if not events:
        return []
    runs: dict[Hashable, _Run] = {}
    for e in events:
        where = (e.data.get("plan"), e.data.get("step"))
        key = ("run", e.id) if e.kind == "DISPATCH" else _run(e)
        if e.kind in ("DISPATCH", "START", "ADOPT"):
            run = runs.setdefault(key, _Run(e))
            run.holder = where
            if e.kind == "START":
                run.start = e
        else:
            runs.pop(key, None)
    labels = []
    for run in reversed(runs.values()):  # the newest first: the oldest before-value wins
        plan, step = run.holder
        if run.start is None and _state(kb, plan, step) != "dispatched":
            continue  # a dispatch logged before runs were named (its end named no run)
        undo = [] if run.start is None else run.start.data.get("undo") or []
        with kb.transaction():
            kb.update_facts(
                add=[Fact(n, tuple(a), v) for n, a, v in undo if v is not None],
                remove=[Fact(n, tuple(a)) for n, a, v in undo if v is None],
            )
            if isinstance(plan, int) and isinstance(step, int):
                with contextlib.suppress(KnowledgeError):  # its plan was deleted
                    kb.set_step_state(plan, step, "cancelled")
            data = {**(run.start or run.began).data, "plan": plan, "step": step}
            if run.start is None:
                data["run"] = run.began.id
            kb.log_event("CANCEL", run.began.subject, {**data, "reason": DIED})
        labels.append(run.began.subject)
    kb.log_event(RECOVERED, "recovery", {"cancelled": labels[::-1]})
    return labels[::-1]


def _state(kb: KnowledgeBase, plan: object, step: object) -> str:
    """The stored state of a plan's step ('' if there is no such step)."""
    if not isinstance(plan, int) or not isinstance(step, int):
        return ""
    try:
        steps = kb.plan(plan).steps
    except KnowledgeError:
        return ""
    return next((s.state for s in steps if s.index == step), "")


def _run(event: Event) -> Hashable:
    """The run a step event belongs to; a log written before runs were named pairs
    events by plan and step."""
    run = event.data.get("run")
    if run is not None:
        return ("run", run)
    return ("step", event.data.get("plan"), event.data.get("step"))
