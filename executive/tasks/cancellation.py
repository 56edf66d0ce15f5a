"""Why a request cannot be scheduled, in words a robot engineer can act on.

Before solving, some requests cannot run whatever the others do: a capability has no
usable provider, the behavior is permanently faulty, the deadline is shorter than the
duration, a start-together partner is unknown or cannot run. After solving, a request
the solver left out is explained by the schedule itself: which scheduled requests
hold the non-shareable functionalities and behaviors it needs within the time it had
(until its deadline, or, for a running task, now), or which start-together partner
it cannot start with.
"""

from __future__ import annotations

from collections.abc import Collection, Mapping, Sequence

from executive.tasks.schedule import Assignment, Request
from knowledge.availability import Availability

SHOWN_HOLDERS = 4  # name this many requests that stand in the way, then count the rest


def precheck(
    requests: Sequence[Request], availability: Availability, faulty: Collection[str]
) -> dict[str, str]:
    """Reasons for the requests that cannot run, whatever the others do."""
    cancelled: dict[str, str] = {}
    known = {r.id for r in requests}
    for r in requests:
        missing = [c for c in r.needs if not availability.available(c)]
        unknown = [t for t in r.together if t not in known]
        if r.behavior in faulty:
            cancelled[r.id] = f"behavior {r.behavior} is permanently faulty"
        elif missing:
            cancelled[r.id] = availability.explain(missing[0])
        elif r.deadline is not None and r.earliest + r.duration > r.deadline:
            cancelled[r.id] = (
                f"deadline {r.deadline:g} s cannot be met: earliest start {r.earliest:g} s"
                f" + expected duration {r.duration:g} s"
            )
        elif unknown:
            cancelled[r.id] = f"must start together with unknown request '{unknown[0]}'"
    # a partner that cannot run takes its whole start-together group with it
    changed = True
    while changed:
        changed = False
        for r in requests:
            partner = next((t for t in r.together if t in cancelled), None)
            if partner is not None and r.id not in cancelled:
                cancelled[r.id] = _with_partner(partner, cancelled[partner])
                changed = True
    return cancelled


def explain(
    left_out: Sequence[str],
    requests: Mapping[str, Request],
    assignments: Mapping[str, Assignment],
    availability: Availability,
) -> dict[str, str]:
    """Reasons for the requests the solver left out, from the schedule it chose."""
    exclusive = {name for name, f in availability.functionalities.items() if not f.shareable} | {
        r.behavior for r in requests.values()
    }
    own = {
        t: _in_the_way(requests[t], requests, assignments, availability, exclusive)
        for t in left_out
    }
    out: dict[str, str] = {}
    for t in left_out:
        request = requests[t]
        partners = [p for p in request.together if p in own]
        shared = {
            p: _mandatory(request, availability, exclusive)
            & _mandatory(requests[p], availability, exclusive)
            for p in partners
        }
        clash = next((p for p in partners if shared[p]), None)
        if clash is not None:
            out[t] = (
                f"cannot start at the same time as '{clash}': both need"
                f" {', '.join(sorted(shared[clash]))}, which serve one task at a time"
            )
        elif own[t]:
            out[t] = own[t]
        else:
            blocked = next((p for p in partners if own[p]), None)
            out[t] = (
                _with_partner(blocked, own[blocked])
                if blocked is not None
                else "no schedule with it found within the time limit"
            )
    return out


def _with_partner(partner: str, reason: str) -> str:
    return f"must start together with '{partner}', which cannot be scheduled: {reason}"


def _in_the_way(
    request: Request,
    requests: Mapping[str, Request],
    assignments: Mapping[str, Assignment],
    availability: Availability,
    exclusive: Collection[str],
) -> str:
    """Who holds what it needs within the time it had; empty if nobody does."""
    if request.running:
        window, intro = (0.0, request.duration), "cannot keep running"
    elif request.deadline is not None:
        window = (request.earliest, request.deadline)
        intro = f"cannot end by its deadline {request.deadline:g} s"
    else:
        return ""
    wanted = _possible(request, availability, exclusive)
    holders = []
    for a in assignments.values():
        held = wanted & ({requests[a.request].behavior} | a.functionalities)
        if held and a.start < window[1] and a.end > window[0]:
            who = f"'{a.request}' (running)" if requests[a.request].running else f"'{a.request}'"
            holders.append(f"{who} holds {', '.join(sorted(held))} from {a.start:g} to {a.end:g} s")
    if not holders:
        return ""
    more = len(holders) - SHOWN_HOLDERS
    shown = "; ".join(holders[:SHOWN_HOLDERS]) + (f"; and {more} more" if more > 0 else "")
    return f"{intro}: {shown}"


def _possible(request: Request, availability: Availability, exclusive: Collection[str]) -> set[str]:
    """Its behavior and every non-shareable functionality any configuration of it may hold."""
    return _closure(request, availability, exclusive, only_sole_providers=False)


def _mandatory(
    request: Request, availability: Availability, exclusive: Collection[str]
) -> set[str]:
    """Its behavior and the non-shareable functionalities every configuration of it holds."""
    return _closure(request, availability, exclusive, only_sole_providers=True)


def _closure(
    request: Request,
    availability: Availability,
    exclusive: Collection[str],
    *,
    only_sole_providers: bool,
) -> set[str]:
    out = {request.behavior}
    todo, seen = list(request.needs), set(request.needs)
    while todo:
        providers = [f for f in availability.providers(todo.pop()) if f.name in availability.usable]
        if only_sole_providers and len(providers) != 1:
            continue
        for f in providers:
            if f.name in exclusive:
                out.add(f.name)
            fresh = set(f.requires) - seen
            seen |= fresh
            todo += fresh
    return out
