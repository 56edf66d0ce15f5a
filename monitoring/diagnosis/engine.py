"""The diagnosis engine: the newest observations against the current model, in clingo.

Only the part of the model upstream of the failed observations can contribute to a
minimal diagnosis, so the engine grounds ``diagnosis.lp`` with the facts of that
region alone: the cost of a diagnosis grows with the region, not with the robot. The
grounded region is kept and observations are externals: while the failed
observations stay inside it (a fault disappears, a verdict within it changes), a new
diagnosis only re-solves. Every answer set of the domain-heuristic enumeration
(``--enum-mode=domRec``) is a subset-minimal diagnosis. When that enumeration runs out
of time, the rest of the time bound goes to the smallest diagnoses (a cardinality
optimisation that enumerates every optimum): a TIMEOUT result still holds all the
most likely diagnoses, however many larger ones there are. Not thread-safe: the
service calls it from one thread.
"""

from __future__ import annotations

import time
from collections.abc import Iterable
from dataclasses import dataclass
from pathlib import Path

import clingo

from executive.protocol import ObservationInfo
from knowledge.asp import Answer, Asp, atom
from knowledge.errors import ConfigError
from monitoring.diagnosis.model import (
    ModelUpdate,
    Observer,
    ObserverType,
    SystemDescription,
)
from monitoring.diagnosis.result import DiagnosisResult, Status, ordered

PROGRAM = Path(__file__).with_name("diagnosis.lp")
OPTIONS = (
    "--heuristic=Domain",
    "--enum-mode=domRec",
    "--project",
    "--models=0",
    "--opt-mode=ignore",
)
SMALLEST_SHARE = 0.25  # of the time bound, kept for the smallest diagnoses


def model_facts(model: SystemDescription, observers: Iterable[Observer]) -> str:
    """The facts of a system description (see ``diagnosis.lp``).

    Candidates are numbered in the order of ``model.candidates``, streams (node, topic)
    in the order of the nodes, observers in the order given: numbers parse, ground
    and solve faster than names.
    """
    candidate = {name: i for i, name in enumerate(model.candidates)}
    streams: dict[str, list[tuple[int, str]]] = {}  # topic -> (stream, publisher)
    out = [f"candidate(0..{len(candidate) - 1}).", f"observer(0..{len(model.observers) - 1})."]
    count = 0
    for node in model.nodes:
        for topic in node.pub_topic:
            streams.setdefault(topic, []).append((count, node.name))
            out.append(f"out({count},{candidate[node.name]}).")
            count += 1
    for node in model.nodes:
        inputs = [t for topic in node.sub_topic for t, _ in streams.get(topic, ())]
        for topic in node.pub_topic:
            for s, publisher in streams[topic]:
                if publisher == node.name:
                    out += [f"dep({s},{t})." for t in inputs]
    for i, observer in enumerate(observers):
        if observer.type.watches_nodes:
            name = observer.resource[0]
            out.append(f"blame({i},{candidate[name]}).")
            watched = model.node(name)
            if observer.type is ObserverType.RESOURCES and watched is not None:
                out += [
                    f"feeds({i},{t})." for m in watched.sub_topic for t, _ in streams.get(m, ())
                ]
            continue
        for topic in observer.topics:
            for s, publisher in streams.get(topic, ()):
                if not observer.callerids or publisher in observer.callerids:
                    out.append(f"watch({i},{s}).")
        if observer.behavior:
            out.append(f"blame({i},{candidate[observer.behavior]}).")
    return "\n".join(out)


@dataclass
class _Grounded:
    """A region of the model, grounded, and what is assigned to its externals."""

    asp: Asp
    nodes: frozenset[str]  # the nodes of the region
    names: tuple[str, ...]  # candidate names by number
    index: dict[Observer, int]  # the observers of the region by number
    assigned: list[tuple[bool, bool]]  # (failed, ok) as assigned, per observer
    bounds: set[int]
    smallest: bool = False  # the part "smallest" is grounded


class DiagnosisEngine:
    """Diagnoses the newest observations against a changing system description.

    Args:
        model: the initial system description (default: empty).
        exonerate: an OK topic observation means that topic is not abnormal.
        max_card: list only diagnoses of at most this many candidates.
        timeout: seconds one diagnosis may take; then the result is TIMEOUT.
    """

    def __init__(
        self,
        model: SystemDescription | None = None,
        *,
        exonerate: bool = False,
        max_card: int | None = None,
        timeout: float | None = None,
    ) -> None:
        self.exonerate = exonerate
        self.max_card = max_card
        self.timeout = timeout
        self._model = SystemDescription()
        self._observers: frozenset[Observer] = frozenset()
        self._rank: dict[Observer, int] = {}  # position in the model
        self._node_rank: dict[str, int] = {}
        self._watchers: dict[str, list[Observer]] = {}  # node -> observers of its streams
        self._observations: dict[Observer, ObservationInfo] = {}
        self._failed: dict[Observer, None] = {}  # observers whose newest observation failed
        self._changed: set[Observer] = set()  # verdicts changed since the last diagnosis
        self._cones: dict[Observer, tuple[frozenset[str], frozenset[Observer]]] = {}
        self._known: dict[tuple[str, tuple[str, ...], tuple[str, ...]], Observer] = {}
        self._grounded: _Grounded | None = None
        if model is not None:
            self.set_model(model)

    # --- the model ----------------------------------------------------------------------

    @property
    def model(self) -> SystemDescription:
        return self._model

    def update(self, update: ModelUpdate) -> SystemDescription:
        """Change the model; raises :class:`ConfigError` (and changes nothing) if invalid."""
        self._install(self._model.apply(update))  # apply checks the result
        return self._model

    def set_model(self, model: SystemDescription) -> None:
        """Replace the model; observations of observers it no longer has are forgotten."""
        problems = model.problems()
        if problems:
            raise ConfigError(problems[0][1])
        self._install(model)

    def _install(self, model: SystemDescription) -> None:
        self._model = model
        self._observers = frozenset(model.observers)
        self._rank = {o: i for i, o in enumerate(model.observers)}
        self._node_rank = {n.name: i for i, n in enumerate(model.nodes)}
        watchers: dict[str, list[Observer]] = {}
        for o in model.observers:
            if o.type.watches_nodes:
                watchers.setdefault(o.resource[0], []).append(o)
                continue
            for name in {p for t in o.topics for p in model.publishers(t)}:
                if not o.callerids or name in o.callerids:
                    watchers.setdefault(name, []).append(o)
        self._watchers = watchers
        self._observations = {o: v for o, v in self._observations.items() if o in self._observers}
        self._failed = {o: None for o, v in self._observations.items() if v.failed}
        self._cones = {}
        self._known = {key: o for o in model.observers for key in o.spellings}
        self._grounded = None

    # --- observations -------------------------------------------------------------------

    def observe(self, info: ObservationInfo) -> bool:
        """Keep an observation if it is the newest of its observer.

        Returns whether the diagnosis may change (the observer's verdict changed).

        Raises:
            ConfigError: the observation's type is unknown, or no observer of the
                model made it.
        """
        key = (info.type, info.resource, info.callerids)
        observer = self._known.get(key)
        if observer is None:  # not spelled as usual: unknown, or caller ids in another order
            observer = Observer.make(*key)
            if observer not in self._observers:
                raise ConfigError(f"observation of {observer}: no such observer in the model")
        old = self._observations.get(observer)
        if old is not None and info.stamp < old.stamp:
            return False
        self._observations[observer] = info
        if old is not None and old.failed == info.failed:
            return False
        if info.failed:
            self._failed[observer] = None
        else:
            self._failed.pop(observer, None)
        self._changed.add(observer)
        return True

    @property
    def observations(self) -> dict[Observer, ObservationInfo]:
        return dict(self._observations)

    def failed(self) -> tuple[Observer, ...]:
        return tuple(self._failed)

    # --- diagnosis ----------------------------------------------------------------------

    def diagnose(self) -> DiagnosisResult:
        """All subset-minimal diagnoses of the newest observations."""
        start = time.perf_counter()
        failed = self.failed()
        if not failed:
            return DiagnosisResult(Status.OK, elapsed=time.perf_counter() - start)
        grounded = self._region(failed)
        self._assign(grounded, self._wanted(grounded, self._changed))
        self._changed.clear()
        self._bound(grounded, self.max_card)
        timeout = self.timeout
        outcome = grounded.asp.solve(
            timeout=None if timeout is None else timeout * (1 - SMALLEST_SHARE)
        )
        answers = list(outcome.answers)
        if outcome.interrupted and timeout is not None:
            # at least its share, also when the interrupted search overran its own
            left = timeout - (time.perf_counter() - start)
            answers += self._smallest(grounded, max(timeout * SMALLEST_SHARE, left))
        names = grounded.names
        found = ordered(
            [
                tuple(names[n] for (n,) in answer.get("faulty") if isinstance(n, int))
                for answer in answers
            ]
        )
        if outcome.interrupted:
            status = Status.TIMEOUT
        elif found:
            status = Status.DIAGNOSED
        elif self.max_card is not None:  # nothing small enough: is there anything at all?
            status = {True: Status.DIAGNOSED, False: Status.INCONSISTENT, None: Status.TIMEOUT}[
                self._consistent(grounded)
            ]
        else:
            status = Status.INCONSISTENT
        conflicts = self._conflicts(grounded) if status is Status.INCONSISTENT else ()
        return DiagnosisResult(status, found, conflicts, failed, time.perf_counter() - start)

    def _cone(self, observer: Observer) -> tuple[frozenset[str], frozenset[Observer]]:
        """The nodes whose faults could reach an observer, and the observers of those
        nodes (kept until the model changes)."""
        known = self._cones.get(observer)
        if known is not None:
            return known
        model = self._model
        nodes: set[str] = set()
        topics: list[tuple[str, tuple[str, ...]]] = []  # (topic, caller ids)
        if observer.type.watches_nodes:
            name = observer.resource[0]
            nodes.add(name)
            node = model.node(name)
            if observer.type is ObserverType.RESOURCES and node is not None:
                topics += [(t, ()) for t in node.sub_topic]
        else:
            topics += [(t, observer.callerids) for t in observer.topics]
        while topics:
            topic, callerids = topics.pop()
            for name in model.publishers(topic):
                if name not in nodes and (not callerids or name in callerids):
                    nodes.add(name)
                    node = model.node(name)
                    topics += [(t, ()) for t in node.sub_topic] if node else []
        near = frozenset(o for n in nodes for o in self._watchers.get(n, ()))
        self._cones[observer] = cone = (frozenset(nodes), near)
        return cone

    def _region(self, failed: tuple[Observer, ...]) -> _Grounded:
        """The grounded region of the failed observations (kept if it still covers them).

        With exoneration, OK observations of the region belong to it too: they clear
        its streams.
        """
        cones = [self._cone(o) for o in failed]
        nodes = frozenset().union(*(c[0] for c in cones))
        near = frozenset().union(*(c[1] for c in cones))  # observers of the region
        observers = set(failed)
        if self.exonerate:
            for o in near:
                info = self._observations.get(o)
                if info is not None and not info.failed and not o.type.watches_nodes:
                    observers.add(o)
        grounded = self._grounded
        if grounded is not None and nodes <= grounded.nodes and observers <= grounded.index.keys():
            return grounded
        # Every observer of the region: a later verdict of one of them re-solves only.
        observers.update(o for o in near if o in self._observations or self.exonerate)
        return self._ground(nodes, observers)

    def _ground(self, nodes: frozenset[str], observers: Iterable[Observer]) -> _Grounded:
        """Ground a region: nodes, and the observers whose verdicts it takes."""
        index = {o: i for i, o in enumerate(sorted(observers, key=self._rank.__getitem__))}
        region = SystemDescription(
            tuple(self._model.nodes[i] for i in sorted(self._node_rank[n] for n in nodes)),
            tuple(index),
        )
        asp = Asp(OPTIONS)
        asp.load(PROGRAM)
        asp.add(model_facts(region, index), source="<model>")
        asp.ground()
        # Externals start false: only observations that say otherwise are assigned.
        self._grounded = _Grounded(
            asp, nodes, region.candidates, index, [(False, False)] * len(index), set()
        )
        self._changed = set(index)  # every observer of a new region is assigned
        return self._grounded

    def _wanted(
        self, grounded: _Grounded, observers: Iterable[Observer]
    ) -> dict[int, tuple[bool, bool]]:
        """(failed, ok) by number for those of the observers in the region, as the newest
        observations say."""
        wanted: dict[int, tuple[bool, bool]] = {}
        for observer in observers:
            i = grounded.index.get(observer)
            if i is not None:
                info = self._observations.get(observer)
                failed = info is not None and info.failed
                wanted[i] = (failed, info is not None and not failed and self.exonerate)
        return wanted

    @staticmethod
    def _assign(grounded: _Grounded, wanted: dict[int, tuple[bool, bool]]) -> None:
        assign = grounded.asp.assign_external
        for i, value in wanted.items():
            old = grounded.assigned[i]
            if old != value:
                if old[0] != value[0]:
                    assign(atom("failed", i), value[0])
                if old[1] != value[1]:
                    assign(atom("ok", i), value[1])
                grounded.assigned[i] = value

    @staticmethod
    def _bound(grounded: _Grounded, max_card: int | None) -> None:
        if max_card is not None and max_card not in grounded.bounds:
            grounded.asp.ground([("bound", (max_card,))])
            grounded.bounds.add(max_card)
        for k in grounded.bounds:
            grounded.asp.assign_external(atom("limit", k), k == max_card)

    @staticmethod
    def _smallest(grounded: _Grounded, timeout: float) -> list[Answer]:
        """Every diagnosis of the smallest size that can be proven so within ``timeout``."""
        asp = grounded.asp
        if not grounded.smallest:
            asp.ground([("smallest", ())])
            grounded.smallest = True
        asp.set("solve.opt_mode", "optN")
        asp.set("solve.enum_mode", "auto")
        try:
            outcome = asp.solve(timeout=timeout, costs=True)
        finally:
            asp.set("solve.opt_mode", "ignore")
            asp.set("solve.enum_mode", "domRec")
        return [a for a in outcome.answers if a.optimal]

    def _consistent(self, grounded: _Grounded) -> bool | None:
        """Whether some diagnosis exists, of any size (None: no answer in time)."""
        self._bound(grounded, None)
        grounded.asp.set("solve.models", "1")
        try:
            return grounded.asp.solve(timeout=self.timeout).satisfiable
        finally:
            grounded.asp.set("solve.models", "0")
            self._bound(grounded, self.max_card)

    def _conflicts(self, grounded: _Grounded) -> tuple[Observer, ...]:
        """A minimal set of observations that no diagnosis explains together.

        The observations become assumptions: clingo's unsatisfiable core is a first
        conflict, and dropping each member that is not needed makes it minimal.
        """
        wanted = self._wanted(grounded, grounded.index)
        count = len(wanted)
        symbols = [atom("failed", i) for i in range(count)] + [atom("ok", i) for i in range(count)]
        values = [wanted[i][0] for i in range(count)] + [wanted[i][1] for i in range(count)]
        present = [s for s, value in zip(symbols, values, strict=True) if value]
        for symbol in symbols:
            grounded.asp.assign_external(symbol, None)
        self._bound(grounded, None)
        grounded.asp.set("solve.models", "1")

        def core_of(chosen: list[clingo.Symbol]) -> list[clingo.Symbol] | None:
            """The failing part of the chosen observations, or None if they are consistent."""
            keep = set(chosen)
            assumptions = [(s, s in keep) for s in symbols]
            outcome = grounded.asp.solve(assumptions=assumptions, timeout=self.timeout)
            if outcome.satisfiable is not False:
                return None
            core = set(outcome.core)
            return [s for s in chosen if s in core] or chosen

        try:
            core = core_of(present) or present
            i = 0
            while i < len(core):
                smaller = core_of(core[:i] + core[i + 1 :])
                if smaller is None:
                    i += 1  # needed
                else:
                    core = smaller
        finally:
            grounded.asp.set("solve.models", "0")
            for symbol, value in zip(symbols, values, strict=True):
                grounded.asp.assign_external(symbol, value)
            self._bound(grounded, self.max_card)
        observers = list(grounded.index)
        numbers = sorted({s.arguments[0].number for s in core})
        return tuple(observers[i] for i in numbers)
