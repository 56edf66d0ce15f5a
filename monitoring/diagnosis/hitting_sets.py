"""Minimal hitting sets of conflicts in clingo: the combinatorial half of a diagnosis.

Candidates that lie in exactly the same conflicts form a class (interchangeable in
every minimal diagnosis). clingo enumerates the minimal sets of classes that hit every
conflict in a template (``diagnosis.lp``) grounded once per size and process, each
problem set through its externals (``member(I,K)``); the domain heuristic with
``--enum-mode=domRec`` makes every answer set subset-minimal. A class set stands for
the diagnoses that take one candidate of each of its classes (:func:`expand`).
Templates are shared by the engines of a process through a small pool, so two threads
never share one; a problem too large for the largest template is grounded on its own.
"""

from __future__ import annotations

import itertools
import os
import threading
import time
from collections.abc import Sequence
from pathlib import Path

from knowledge.asp import Asp, atom

PROGRAM = Path(__file__).with_name("diagnosis.lp")
OPTIONS = (
    "--heuristic=Domain",
    "--enum-mode=domRec",
    "--project",
    "--models=0",
    "--opt-mode=ignore",
)
SMALLEST_SHARE = 0.25  # of the time bound, kept for the smallest diagnoses
KEPT = 10_000  # diagnoses of the smallest size expanded even past the time bound
CHUNK = 4_096  # diagnoses expanded between looks at the clock


class _HittingSets:
    """``diagnosis.lp`` grounded for some conflict and class slots, one problem at a
    time; or grounded for one problem (``members`` given, no slots)."""

    def __init__(
        self, conflicts: int, classes: int, members: set[tuple[int, int]] | None = None
    ) -> None:
        self.conflicts = conflicts
        self.classes = classes
        self.asp = Asp(OPTIONS)
        self.asp.load(PROGRAM)
        if members is None:
            self.asp.ground([("slots", (conflicts, classes))])
        else:
            self.asp.add_facts(
                [atom("member", i, k) for i, k in members]
                + [atom("class", k) for k in range(classes)]
            )
            self.asp.ground([("base", ()), ("slots", (0, 0))])
        self.members: set[tuple[int, int]] = members or set()  # as assigned
        self.pooled = members is None
        self.bounds: set[int] = set()

    def pose(self, members: set[tuple[int, int]], max_card: int | None) -> None:
        """Set a problem: (conflict, class) memberships, and the size bound."""
        assign = self.asp.assign_external
        for i, k in self.members - members:
            assign(atom("member", i, k), False)
        for i, k in members - self.members:
            assign(atom("member", i, k), True)
        self.members = members
        if max_card is not None and max_card not in self.bounds:
            self.asp.ground([("bound", (max_card,))])
            self.bounds.add(max_card)
        for k in self.bounds:
            assign(atom("limit", k), k == max_card)

    def enumerate(self, timeout: float | None) -> tuple[list[tuple[int, ...]], bool]:
        """Every minimal hitting set (as classes), and whether the time bound cut it."""
        outcome = self.asp.solve(timeout=timeout)
        return [_picked(a.get("pick")) for a in outcome.answers], outcome.interrupted

    def least(self, timeout: float) -> list[tuple[int, ...]]:
        """Every hitting set of the smallest size that can be proven so within ``timeout``.

        Core-guided optimisation (``usc``) finds the smallest from below, where the
        enumeration's heuristic would lead branch-and-bound through large sets first.
        The solver's options stay changed: the template is not reused.
        """
        self.pooled = False
        asp = self.asp
        asp.ground([("smallest", ())])
        asp.set("solve.opt_mode", "optN")
        asp.set("solve.enum_mode", "auto")
        asp.set("solver.opt_strategy", "usc")
        outcome = asp.solve(timeout=timeout, costs=True)
        return [_picked(a.get("pick")) for a in outcome.answers if a.optimal]


def _picked(rows: Sequence[tuple[object, ...]]) -> tuple[int, ...]:
    return tuple(k for (k,) in rows if isinstance(k, int))


class _Templates:
    """Grounded templates shared by the engines of a process: grounding one costs more
    than a diagnosis, and it does not depend on the model. Each solve costs in
    proportion to the template's slots, so a problem takes the smallest template that
    fits (slots in powers of two). An engine takes one for a diagnosis and gives it
    back, so engines in different threads never share one."""

    def __init__(self) -> None:
        self._lock = threading.Lock()
        self._free: dict[tuple[int, int], list[_HittingSets]] = {}
        os.register_at_fork(after_in_child=self._free.clear)  # no control crosses a fork

    def take(self, conflicts: int, classes: int, members: set[tuple[int, int]]) -> _HittingSets:
        """A template for a problem (grounded for it alone when templates grow too large)."""
        size = (_slots(conflicts), _slots(classes))
        if size[0] * size[1] > TEMPLATE_SLOTS:
            return _HittingSets(conflicts, classes, members)
        with self._lock:
            free = self._free.get(size)
            if free:
                return free.pop()
        return _HittingSets(*size)

    def give(self, template: _HittingSets) -> None:
        if not template.pooled:
            return
        with self._lock:
            free = self._free.setdefault((template.conflicts, template.classes), [])
            if len(free) < TEMPLATES:
                free.append(template)


def _slots(count: int) -> int:
    """The smallest power of two that holds ``count`` (at least 2)."""
    return max(2, 1 << (count - 1).bit_length())


TEMPLATES = 2  # templates of one size kept for reuse
TEMPLATE_SLOTS = 1024  # conflicts x classes of the largest template (64 x 64: 20 ms to ground,
# 1.2 ms a solve): a larger problem is grounded on its own
POOL = _Templates()


def classes_of(
    conflicts: list[frozenset[str]],
) -> tuple[list[list[str]], set[tuple[int, int]], int]:
    """The classes of a hitting-set problem: candidates that lie in the same minimal
    conflicts, each sorted; the (conflict, class) memberships; the number of conflicts.

    A conflict that contains another is dropped (whatever hits the smaller hits it).
    """
    minimal: list[frozenset[str]] = []
    for conflict in sorted(set(conflicts), key=len):
        if not any(m <= conflict for m in minimal):
            minimal.append(conflict)
    signature: dict[str, list[int]] = {}
    for i, conflict in enumerate(minimal):
        for name in conflict:
            signature.setdefault(name, []).append(i)
    groups: dict[tuple[int, ...], list[str]] = {}
    for name, where in signature.items():
        groups.setdefault(tuple(where), []).append(name)
    members = {(i, k) for k, where in enumerate(groups) for i in where}
    return [sorted(g) for g in groups.values()], members, len(minimal)


def expand(
    chosen: list[tuple[int, ...]], classes: list[list[str]], deadline: float | None
) -> tuple[list[tuple[str, ...]], bool]:
    """The diagnoses that class sets stand for (one candidate of each class), sorted,
    smallest first; and whether the deadline cut the expansion.

    Sorting them costs about as much again as making them, so the expansion stops
    when the time it has taken, spent once more, would pass the deadline. The
    diagnoses of the smallest size are expanded regardless, up to ``KEPT``.
    """
    out: list[tuple[str, ...]] = []
    ordered = sorted(set(chosen), key=len)
    least = len(ordered[0]) if ordered else 0
    begin = time.perf_counter()
    cut = False
    for picked in ordered:
        keep = len(picked) == least
        for n, combination in enumerate(itertools.product(*(classes[k] for k in picked))):
            if n % CHUNK == 0 and deadline is not None and (not keep or len(out) >= KEPT):
                now = time.perf_counter()
                if 2 * now - begin > deadline:
                    cut = True
                    break
            out.append(tuple(sorted(combination)))
        if cut:
            break
    out.sort()
    out.sort(key=len)  # stable: by name within a size
    return out, cut
