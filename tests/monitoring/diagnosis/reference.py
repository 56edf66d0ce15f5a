"""A brute-force reference diagnoser, written from the definition and nothing else.

For every set of faulty candidates and every set of abnormal message streams (a
stream is one node's messages on one topic) it checks the definition literally:
every stream of a faulty node is abnormal; every abnormal stream is derivable from
faulty nodes (well-founded: its node is faulty or has an abnormal input stream
derived before it); with exoneration no stream an OK topic observation watches is
abnormal; every failed observation is explained. The diagnoses are the consistent
candidate sets that have no consistent proper subset. Exponential: small models only.
"""

from __future__ import annotations

from collections.abc import Iterable
from itertools import chain, combinations

from executive.bus.payloads import ObservationInfo
from monitoring.diagnosis.model import ModelObserver, ObserverType, SystemDescription

Stream = tuple[str, str]  # (node, topic)


def _subsets(items: list[str]) -> Iterable[frozenset[str]]:
    return (
        frozenset(c)
        for c in chain.from_iterable(combinations(items, k) for k in range(len(items) + 1))
    )


def _watched(model: SystemDescription, observer: ModelObserver) -> set[Stream]:
    out: set[Stream] = set()
    for topic in observer.topics:
        for node in model.publishers(topic):
            if not observer.callerids or node in observer.callerids:
                out.add((node, topic))
    return out


def _well_founded(
    model: SystemDescription, faulty: frozenset[str], abnormal: frozenset[Stream]
) -> bool:
    derived: set[Stream] = set()
    changed = True
    while changed:
        changed = False
        for node, topic in abnormal - derived:
            spec = model.node(node)
            assert spec is not None
            inputs = {t for _, t in derived}
            if node in faulty or any(t in inputs for t in spec.sub_topic):
                derived.add((node, topic))
                changed = True
    return derived == abnormal


def _explained(
    model: SystemDescription,
    observer: ModelObserver,
    faulty: frozenset[str],
    abnormal: frozenset[Stream],
) -> bool:
    topics = {t for _, t in abnormal}
    if observer.type is ObserverType.COMPONENT:
        return observer.resource[0] in faulty
    if observer.type is ObserverType.RESOURCES:
        node = model.node(observer.resource[0])
        assert node is not None
        return node.name in faulty or any(t in topics for t in node.sub_topic)
    if observer.behavior is not None and observer.behavior in faulty:
        return True
    return bool(_watched(model, observer) & abnormal)


def consistent(
    model: SystemDescription,
    observations: dict[ModelObserver, ObservationInfo],
    faulty: frozenset[str],
    *,
    exonerate: bool,
) -> bool:
    """Whether some assignment of abnormal streams fits these faulty candidates."""
    streams = [(n.name, t) for n in model.nodes for t in n.pub_topic]
    forced = {(n, t) for n, t in streams if n in faulty}
    cleared: set[Stream] = set()
    if exonerate:
        for observer, info in observations.items():
            if not info.failed:
                cleared |= _watched(model, observer)
    free = [s for s in streams if s not in forced]
    for extra in chain.from_iterable(combinations(free, k) for k in range(len(free) + 1)):
        abnormal = frozenset(forced | set(extra))
        if abnormal & cleared or not _well_founded(model, faulty, abnormal):
            continue
        if all(
            _explained(model, o, faulty, abnormal)
            for o, info in observations.items()
            if info.failed
        ):
            return True
    return False


def diagnoses(
    model: SystemDescription, observations: dict[ModelObserver, ObservationInfo], *, exonerate: bool
) -> set[frozenset[str]]:
    """Every subset-minimal consistent set of faulty candidates."""
    good = [
        d
        for d in _subsets(list(model.candidates))
        if consistent(model, observations, d, exonerate=exonerate)
    ]
    return {d for d in good if not any(other < d for other in good)}
