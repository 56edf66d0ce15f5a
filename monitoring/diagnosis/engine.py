"""The diagnosis engine: the newest observations against the current model, in clingo.

A diagnosis is a set of faulty candidates that explains every failed observation; the
engine lists the subset-minimal ones (Reiter's consistency-based diagnosis). Under
the model's semantics (abnormal streams derived from faulty nodes along the
communication graph, well-founded, cut by cleared streams under exoneration) a set
of candidates explains a failed observation exactly when it holds one of the
observation's *conflict*: the candidates from which a path of abnormal streams can
reach what it watches (or that it blames directly). So the minimal diagnoses are the
minimal hitting sets of the conflicts.

The engine computes each conflict from the graph (upstream cones, kept per observer
until the model changes), drops conflicts that contain another, and merges the
candidates that lie in exactly the same conflicts into classes: those are
interchangeable in every minimal diagnosis. clingo enumerates the minimal sets of
classes that hit every conflict (:mod:`.hitting_sets`, ``diagnosis.lp``: a template grounded once, each
problem set through its externals, the domain heuristic ``--enum-mode=domRec``
making every answer set subset-minimal); each class set stands for the diagnoses
that pick one candidate of each of its classes, expanded smallest first. When the
enumeration runs out of time, the rest of the time bound goes to the smallest
diagnoses (a cardinality optimisation that enumerates every optimum): a TIMEOUT
result still holds all the most likely diagnoses, however many larger ones there
are. Not thread-safe: the service calls it from one thread.
"""

from __future__ import annotations

import time
from collections.abc import Container

from executive.bus.payloads import ObservationInfo
from knowledge.errors import ConfigError
from monitoring.diagnosis.hitting_sets import POOL, SMALLEST_SHARE, classes_of, expand
from monitoring.diagnosis.model import (
    ModelObserver,
    ModelUpdate,
    ObserverType,
    SystemDescription,
)
from monitoring.diagnosis.result import DiagnosisResult, Status

Stream = tuple[str, str]  # what one node publishes on one topic: (node, topic)


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
        self._exonerate = exonerate
        self.max_card = max_card
        self.timeout = timeout
        self._model = SystemDescription()
        self._observers: frozenset[ModelObserver] = frozenset()
        self._rank: dict[ModelObserver, int] = {}  # position in the model
        self._observations: dict[ModelObserver, ObservationInfo] = {}
        self._failed: dict[ModelObserver, None] = {}  # observers whose newest observation failed
        # with exoneration: the OK topic observers by the streams they clear
        self._clearing: dict[Stream, set[ModelObserver]] = {}
        self._upstream: dict[str, frozenset[str]] = {}  # node -> nodes that can reach it
        self._cones: dict[ModelObserver, frozenset[str]] = {}  # both kept until the model changes
        self._streams: dict[ModelObserver, list[Stream]] = {}
        self._known: dict[tuple[str, tuple[str, ...], tuple[str, ...]], ModelObserver] = {}
        if model is not None:
            self.set_model(model)

    @property
    def exonerate(self) -> bool:
        """Whether an OK topic observation means that its topics are not abnormal."""
        return self._exonerate

    @exonerate.setter
    def exonerate(self, value: bool) -> None:
        self._exonerate = value
        self._index_clearing()

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
        self._observations = {o: v for o, v in self._observations.items() if o in self._observers}
        self._failed = {o: None for o, v in self._observations.items() if v.failed}
        self._upstream = {}
        self._cones = {}
        self._streams = {}
        self._index_clearing()
        self._known = {key: o for o in model.observers for key in o.spellings}

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
            observer = ModelObserver.make(*key)
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
            if old is not None and self._exonerate:
                self._unclear(observer)
        else:
            self._failed.pop(observer, None)
            if self._exonerate:
                self._clear(observer)
        return True

    def _index_clearing(self) -> None:
        self._clearing = {}
        if self._exonerate:
            for observer, info in self._observations.items():
                if not info.failed:
                    self._clear(observer)

    def _clear(self, observer: ModelObserver) -> None:
        """Note an OK topic observer: with exoneration, its streams are not abnormal."""
        for stream in self._watched(observer):
            self._clearing.setdefault(stream, set()).add(observer)

    def _unclear(self, observer: ModelObserver) -> None:
        for stream in self._watched(observer):
            by = self._clearing.get(stream)
            if by is not None:
                by.discard(observer)
                if not by:
                    del self._clearing[stream]

    @property
    def observations(self) -> dict[ModelObserver, ObservationInfo]:
        return dict(self._observations)

    def failed(self) -> tuple[ModelObserver, ...]:
        return tuple(self._failed)

    # --- diagnosis ----------------------------------------------------------------------

    def diagnose(self) -> DiagnosisResult:
        """All subset-minimal diagnoses of the newest observations."""
        start = time.perf_counter()
        failed = self.failed()
        if not failed:
            return DiagnosisResult(Status.OK, elapsed=time.perf_counter() - start)
        cleared = {name for name, _ in self._clearing}  # nodes with a cleared stream
        conflicts = [self._conflict(o, cleared) for o in failed]
        for observer, conflict in zip(failed, conflicts, strict=True):
            if not conflict:
                return DiagnosisResult(
                    Status.INCONSISTENT,
                    conflicts=self._conflicting(observer),
                    failed=failed,
                    elapsed=time.perf_counter() - start,
                )
        classes, members, count = classes_of(conflicts)
        template = POOL.take(count, len(classes), members)
        template.pose(members, self.max_card)
        timeout = self.timeout
        chosen, interrupted = template.enumerate(
            None if timeout is None else timeout * (1 - SMALLEST_SHARE)
        )
        if interrupted and timeout is not None:
            # at least its share, also when the interrupted search overran its own
            left = timeout - (time.perf_counter() - start)
            chosen += template.least(max(timeout * SMALLEST_SHARE, left))
        POOL.give(template)  # only after a clean use: a failed one is dropped
        deadline = None if self.timeout is None else start + self.timeout
        found, cut = expand(chosen, classes, deadline)
        # With a size bound and nothing found, every diagnosis is larger: there are
        # some, as every conflict is non-empty.
        status = Status.TIMEOUT if interrupted or cut else Status.DIAGNOSED
        return DiagnosisResult(
            status, tuple(found), failed=failed, elapsed=time.perf_counter() - start
        )

    def _watched(self, observer: ModelObserver) -> list[Stream]:
        """The streams a topic observer watches (none for a node observer)."""
        streams = self._streams.get(observer)
        if streams is None:
            publishers = self._model.publishers
            ids = observer.callerids
            streams = self._streams[observer] = [
                (p, t) for t in observer.topics for p in publishers(t) if not ids or p in ids
            ]
        return streams

    def _conflict(self, observer: ModelObserver, cleared: set[str]) -> frozenset[str]:
        """The candidates that could explain an observer's failure, given the nodes
        that publish a cleared stream."""
        cone = self._cones.get(observer)
        if cone is None:
            cone = self._cones[observer] = self._cone(observer)
        if not cone.isdisjoint(cleared):
            return self._reach(observer, self._clearing)
        return cone

    def _cone(self, observer: ModelObserver) -> frozenset[str]:
        """The candidates that could explain an observer's failure with nothing cleared."""
        if observer.type is ObserverType.COMPONENT:
            return frozenset(observer.resource)
        if observer.type is ObserverType.RESOURCES:
            return self._upstream_of(observer.resource[0])
        cone = frozenset().union(*(self._upstream_of(p) for p, _ in self._watched(observer)))
        return cone | {observer.behavior} if observer.behavior else cone

    def _upstream_of(self, name: str) -> frozenset[str]:
        """A node and every node whose faults can reach its outputs (kept per node; a
        search stops at nodes already known)."""
        known = self._upstream.get(name)
        if known is not None:
            return known
        found: set[str] = {name}
        stack = [name]
        while stack:
            for p, _ in self._inputs(stack.pop()):
                if p not in found:
                    up = self._upstream.get(p)
                    if up is None:
                        found.add(p)
                        stack.append(p)
                    else:
                        found |= up
        self._upstream[name] = cone = frozenset(found)
        return cone

    def _reach(self, observer: ModelObserver, cleared: Container[Stream]) -> frozenset[str]:
        """The candidates from which abnormal streams can reach what an observer
        watches (or that it blames), none of them through a cleared stream."""
        blamed: list[str] = []
        if observer.type.watches_nodes:
            name = observer.resource[0]
            blamed.append(name)
            starts = self._inputs(name) if observer.type is ObserverType.RESOURCES else []
        else:
            starts = list(self._watched(observer))
            if observer.behavior:
                blamed.append(observer.behavior)
        seen: set[Stream] = set()
        nodes: dict[str, None] = dict.fromkeys(blamed)
        stack = starts
        while stack:
            stream = stack.pop()
            if stream in seen or stream in cleared:
                continue
            seen.add(stream)
            name = stream[0]
            if name not in nodes:
                nodes[name] = None
                stack += self._inputs(name)
        # a faulty node makes all its streams abnormal: one that publishes a cleared
        # stream is not faulty
        return frozenset(n for n in nodes if not any(s in cleared for s in self._outputs(n)))

    def _inputs(self, name: str) -> list[Stream]:
        """The streams a node subscribes (none for a behavior)."""
        model = self._model
        node = model.node(name)
        subscribed = node.sub_topic if node is not None else ()
        return [(p, t) for t in subscribed for p in model.publishers(t)]

    def _outputs(self, name: str) -> list[Stream]:
        """The streams a node publishes (none for a behavior)."""
        node = self._model.node(name)
        return [(name, t) for t in node.pub_topic] if node is not None else []

    def _conflicting(self, observer: ModelObserver) -> tuple[ModelObserver, ...]:
        """A minimal set of observations that no diagnosis explains together: a failed
        observer nothing can explain, and the OK observations that clear its paths."""
        clearing = self._clearing
        needed = sorted(
            {
                o
                for n in self._cone(observer)
                for s in self._outputs(n)
                for o in clearing.get(s, ())
            },
            key=self._rank.__getitem__,
        )
        i = 0
        while i < len(needed):
            rest = needed[:i] + needed[i + 1 :]
            if self._reach(observer, {s for o in rest for s in self._watched(o)}):
                i += 1  # needed
            else:
                needed = rest
        return tuple(sorted([observer, *needed], key=self._rank.__getitem__))
