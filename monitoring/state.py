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
from typing import Annotated, Any

from executive.bus.payloads import NO_STATE_FITS
from knowledge.conventions import Convert, Label
from knowledge.typed_reader import MISSING, Place, open_entry, read_value
from monitoring.check import Check, CheckSpec
from monitoring.filter import FilterState, Text


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


def states_checking(
    *quantities: str, aliases: Mapping[str, str] | None = None, every: bool = False
) -> Convert:
    """How the ``states`` of an observed resource are read (``Annotated`` metadata of a
    ``tuple[ObserverState, ...]``; a state without a name or number is left out).

    Args:
        quantities: the quantities a state may check (keys of a state entry).
        aliases: legacy key spellings, e.g. ``{"frequenzy": "frequency"}``.
        every: each state must check every quantity (else: at least one).
    """
    spellings = aliases or {}

    def read_states(value: Any, place: Place) -> Any:
        names: set[str] = set()

        def read_state(value: Any, place: Place) -> Any:
            entry = open_entry(value, place.source, place.path, place.label or "", place=place)
            if entry is None:
                return MISSING
            name = entry.read("state", Text, None, required=True)
            number = entry.read("number", int, None, required=True)
            checks: dict[str, Check] = {}
            for key in (*quantities, *spellings):
                quantity = spellings.get(key, key)
                if entry.has(key) and quantity in checks:
                    entry.known(key)
                    entry.error(key, f"{entry.what} checks {quantity} twice ('{key}')")
                    continue
                label = Label(f"the {quantity} check of {{what}}")
                check = entry.read(key, Annotated[CheckSpec, label], None)
                if check is not None:
                    checks[quantity] = check
            written = {spellings.get(k, k) for k in entry.written if entry.has(k)}
            missing = [q for q in quantities if q not in checks and q not in written]
            if every and missing:
                entry.error(None, f"{entry.what} has no '{missing[0]}' check")
            elif len(missing) == len(quantities):
                given = ", ".join(quantities)
                entry.error(None, f"{entry.what} checks nothing (give one of: {given})")
            entry.close()
            if name is not None and name in names:
                entry.error("state", f"{entry.what}: state '{name}' is defined twice")
            if name is None or number is None:
                return MISSING
            names.add(name)
            return ObserverState(name, number, checks)

        each = Annotated[
            tuple[Annotated[Any, Convert(read_state)], ...], Label("state {n} of {what}")
        ]
        return read_value(each, value, place)

    return Convert(read_states)
