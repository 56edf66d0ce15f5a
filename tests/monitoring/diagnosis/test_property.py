"""On random small models the engine's diagnoses equal the brute-force reference's."""

from __future__ import annotations

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from executive.bus.payloads import ObservationInfo
from monitoring.diagnosis.engine import DiagnosisEngine
from monitoring.diagnosis.model import ModelObserver, Node, SystemDescription
from monitoring.diagnosis.result import Status
from tests.monitoring.diagnosis.reference import diagnoses as reference

TOPICS = ["t0", "t1", "t2", "t3"]


@st.composite
def situations(draw: st.DrawFn) -> tuple[SystemDescription, list[ObservationInfo], bool]:
    """A model of 2-4 nodes (cycles and shared topics allowed), observers, observations."""
    count = draw(st.integers(2, 4))
    nodes = []
    for i in range(count):
        pub = draw(st.lists(st.sampled_from(TOPICS), min_size=0, max_size=2, unique=True))
        sub = draw(st.lists(st.sampled_from(TOPICS), min_size=0, max_size=2, unique=True))
        nodes.append(Node(f"n{i}", tuple(sub), tuple(pub)))
    names = [n.name for n in nodes]
    published = sorted({t for n in nodes for t in n.pub_topic})
    options: list[ModelObserver] = [
        ModelObserver.make(k, [n]) for n in names for k in ("component", "resources")
    ]
    for topic in published:
        publishers = [n.name for n in nodes if topic in n.pub_topic]
        options.append(ModelObserver.make("frequency", [topic]))
        options.append(ModelObserver.make("timeout", [topic], [publishers[0]]))
    for a in published:
        for b in published:
            if a < b:
                options.append(ModelObserver.make("timing", [a, b]))
                options.append(ModelObserver.make("movement", [a, b, "slip"]))
    observers = draw(st.lists(st.sampled_from(options), min_size=1, max_size=5, unique=True))
    model = SystemDescription(tuple(nodes), tuple(observers))
    infos = [
        ObservationInfo(o.type.value, o.resource, v, callerids=o.callerids)
        for o in observers
        if (v := draw(st.sampled_from([-1, -1, 0, None]))) is not None
    ]
    return model, infos, draw(st.booleans())


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(situations())
def test_the_engine_finds_exactly_the_minimal_diagnoses_of_the_definition(
    situation: tuple[SystemDescription, list[ObservationInfo], bool],
) -> None:
    model, infos, exonerate = situation
    engine = DiagnosisEngine(model, exonerate=exonerate)
    for info in infos:
        engine.observe(info)
    result = engine.diagnose()
    expected = {
        tuple(sorted(d)) for d in reference(model, engine.observations, exonerate=exonerate)
    }
    if result.status is Status.OK:
        assert expected == {()}
    elif result.status is Status.INCONSISTENT:
        assert expected == set()
        # The conflicting observations admit no diagnosis, and each one is needed.
        conflicting = {o: engine.observations[o] for o in result.conflicts}
        assert not reference(model, conflicting, exonerate=exonerate)
        for o in result.conflicts:
            rest = {k: v for k, v in conflicting.items() if k != o}
            assert reference(model, rest, exonerate=exonerate)
    else:
        assert result.status is Status.DIAGNOSED
        assert set(result.diagnoses) == expected


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(situations(), st.data())
def test_a_running_engine_stays_exact_as_observations_change(
    situation: tuple[SystemDescription, list[ObservationInfo], bool], data: st.DataObject
) -> None:
    model, infos, exonerate = situation
    engine = DiagnosisEngine(model, exonerate=exonerate)
    for info in infos:
        engine.observe(info)
    engine.diagnose()
    for step in range(1, 5):
        observer = data.draw(st.sampled_from(model.observers))
        value = data.draw(st.sampled_from([-1, 0]))
        engine.observe(
            ObservationInfo(
                observer.type.value,
                observer.resource,
                value,
                callerids=observer.callerids,
                stamp=step,
            )
        )
        result = engine.diagnose()
        expected = {
            tuple(sorted(d)) for d in reference(model, engine.observations, exonerate=exonerate)
        }
        if result.status is Status.OK:
            assert expected == {()}
        elif result.status is Status.INCONSISTENT:
            assert expected == set()
        else:
            assert set(result.diagnoses) == expected
