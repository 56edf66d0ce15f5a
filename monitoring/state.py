"""Named states of an observed resource and how measurements are classified into them.

A state (thesis 6.2.5) has a name, a number (negative: a fault) and one hypothesis
check per measured quantity::

    states:
      - {state: ok, number: 1, frequency: {type: in_between, lower_bound: 8, upper_bound: 12}}
      - {state: slow, number: -5, frequency: {type: less_than, less_than: 8}}

The first state (in the order written) whose checks all pass is the observation;
when none fits, the observation is ``NO_STATE_FITS``.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

from executive.bus.payloads import NO_STATE_FITS
from monitoring.check import Check, read_check
from monitoring.config_entry import Entry
from monitoring.filter import FilterState


@dataclass(frozen=True)
class ObserverState:
    name: str
    number: int
    checks: Mapping[str, Check]  # measured quantity -> check

    def fits(self, measured: Mapping[str, FilterState]) -> bool:
        """Whether every check passes (a quantity not measured yet fails its check)."""
        for quantity, check in self.checks.items():
            state = measured.get(quantity)
            if state is None or not check.passes(state):
                return False
        return True


@dataclass(frozen=True)
class Verdict:
    """What an observer says about a resource: a number (negative: fault), a name, details."""

    number: int
    name: str
    detail: str = ""


def classify(
    states: tuple[ObserverState, ...], measured: Mapping[str, FilterState], note: str = ""
) -> Verdict:
    """The first state the measurement fits; ``note`` follows the measured values."""
    shown = ", ".join(f"{q} {s.value:.6g}" for q, s in measured.items()) + note
    for state in states:
        if state.fits(measured):
            return Verdict(state.number, state.name, shown)
    wanted = "; ".join(
        f"{s.name}: " + ", ".join(f"{q} {c}" for q, c in s.checks.items()) for s in states
    )
    return Verdict(NO_STATE_FITS, "no state fits", f"{shown}; fits none of: {wanted}")


def read_states(
    owner: Entry,
    quantities: tuple[str, ...],
    *,
    aliases: Mapping[str, str] | None = None,
    every: bool = False,
) -> tuple[ObserverState, ...]:
    """The ``states`` of an observed resource.

    Args:
        owner: the mapping that holds ``states``.
        quantities: the quantities a state may check (keys of a state entry).
        aliases: legacy key spellings, e.g. ``{"frequenzy": "frequency"}``.
        every: each state must check every quantity (else: at least one).
    """
    aliases = aliases or {}
    out: list[ObserverState] = []
    names: set[str] = set()
    for entry in owner.entries("states", f"state {{n}} of {owner.what}", required=True):
        if not entry.valid:
            continue
        name = entry.text("state", required=True)
        number = entry.integer("number", required=True)
        checks: dict[str, Check] = {}
        for key in (*quantities, *aliases):
            quantity = aliases.get(key, key)
            sub = entry.entry(key, f"the {quantity} check of {entry.what}")
            if sub is None:
                continue
            if quantity in checks:
                entry.error(key, f"{entry.what} checks {quantity} twice ('{key}')")
                continue
            check = read_check(sub)
            if check is not None:
                checks[quantity] = check
        missing = [q for q in quantities if q not in checks and not _has(entry, q, aliases)]
        if every and missing:
            entry.error(None, f"{entry.what} has no '{missing[0]}' check")
        elif len(missing) == len(quantities):
            entry.error(None, f"{entry.what} checks nothing (give one of: {', '.join(quantities)})")
        entry.close()
        if name is not None and name in names:
            entry.error("state", f"{entry.what}: state '{name}' is defined twice")
        if name is not None and number is not None:
            names.add(name)
            out.append(ObserverState(name, number, checks))
    return tuple(out)


def _has(entry: Entry, quantity: str, aliases: Mapping[str, str]) -> bool:
    """Whether the entry names a check of a quantity (valid or not)."""
    return entry.has(quantity) or any(entry.has(k) for k, q in aliases.items() if q == quantity)
