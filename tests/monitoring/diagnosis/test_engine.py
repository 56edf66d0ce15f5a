"""The diagnosis engine against the registry of example models, and on its own terms."""

from __future__ import annotations

import pytest

from executive.bus.payloads import ObservationInfo
from knowledge.errors import ConfigError
from monitoring.diagnosis.engine import DiagnosisEngine
from monitoring.diagnosis.model import (
    ModelObserver,
    ModelUpdate,
    Node,
    SystemDescription,
    UpdateAction,
)
from monitoring.diagnosis.result import Status
from tests.monitoring.diagnosis.cases import CASES, THESIS_NODES, Case
from tests.monitoring.diagnosis.reference import diagnoses as reference


def run(case: Case) -> tuple[Status, set[tuple[str, ...]], set[str]]:
    engine = DiagnosisEngine(case.model, exonerate=case.exonerate, max_card=case.max_card)
    for info in case.infos:
        engine.observe(info)
    result = engine.diagnose()
    return result.status, set(result.diagnoses), {str(o) for o in result.conflicts}


@pytest.mark.parametrize("case", CASES, ids=lambda c: c.name)
def test_the_engine_finds_the_expected_diagnoses(case: Case) -> None:
    status, found, conflicts = run(case)
    assert status.value == case.status
    assert found == set(case.expected)
    assert conflicts == set(case.conflicts)


@pytest.mark.parametrize("case", [c for c in CASES if c.max_card is None], ids=lambda c: c.name)
def test_the_reference_agrees_with_the_registry(case: Case) -> None:
    engine = DiagnosisEngine(case.model)
    for info in case.infos:
        engine.observe(info)
    found = reference(case.model, engine.observations, exonerate=case.exonerate)
    # With nothing failed, the empty set is the one diagnosis (the engine says OK).
    expected = {()} if case.status == "OK" else set(case.expected)
    assert {tuple(sorted(d)) for d in found} == expected


def thesis() -> DiagnosisEngine:
    return DiagnosisEngine(CASES[0].model)


def test_a_changed_observation_is_rediagnosed() -> None:
    engine = thesis()
    assert engine.observe(ObservationInfo("hz", ("m4",), -1, stamp=1.0))
    assert set(engine.diagnose().diagnoses) == {("N1",), ("N2",), ("N3",), ("N4",)}
    assert engine.observe(ObservationInfo("hz", ("m4",), 0, stamp=2.0))
    assert engine.observe(ObservationInfo("component", ("N4",), -1, stamp=2.0))
    assert engine.diagnose().diagnoses == (("N4",),)


def test_an_older_observation_does_not_replace_a_newer_one() -> None:
    engine = thesis()
    engine.observe(ObservationInfo("hz", ("m4",), -1, stamp=2.0))
    assert not engine.observe(ObservationInfo("hz", ("m4",), 0, stamp=1.0))
    assert engine.diagnose().status is Status.DIAGNOSED


def test_a_repeated_verdict_does_not_ask_for_a_new_diagnosis() -> None:
    engine = thesis()
    assert engine.observe(ObservationInfo("hz", ("m4",), -1, stamp=1.0))
    assert not engine.observe(ObservationInfo("hz", ("m4",), -2, stamp=2.0))


def test_an_observation_of_an_unknown_type_is_refused_with_the_reason() -> None:
    with pytest.raises(ConfigError, match="unknown observer type 'hzz'"):
        thesis().observe(ObservationInfo("hzz", ("m4",), -1))


def test_an_observation_no_observer_made_is_refused() -> None:
    with pytest.raises(ConfigError, match=r"timeout\[m4\]: no such observer"):
        thesis().observe(ObservationInfo("timeout", ("m4",), -1))


def test_the_model_grows_as_the_thesis_example_starts_its_nodes() -> None:
    engine = DiagnosisEngine()
    for (name, sub, pub), observers in zip(
        THESIS_NODES,
        [
            [("frequency", ("m1",))],
            [("frequency", ("m2",))],
            [("frequency", ("m3",)), ("resources", ("N3",))],
            [("component", ("N4",))],
        ],
        strict=True,
    ):
        engine.update(
            ModelUpdate(
                UpdateAction.ADD,
                (Node(name, sub, pub),),
                tuple(ModelObserver.make(t, r) for t, r in observers),
            )
        )
    assert [n.name for n in engine.model.nodes] == ["N1", "N2", "N3", "N4"]
    engine.observe(ObservationInfo("frequency", ("m3",), -1))
    assert set(engine.diagnose().diagnoses) == {("N1",), ("N2",), ("N3",)}


def test_removing_a_node_with_its_observers_restores_the_earlier_model() -> None:
    engine = DiagnosisEngine()
    before = SystemDescription(
        (Node("N1", (), ("m1",)), Node("N2", (), ("m2",))), (ModelObserver.make("hz", ["m1"]),)
    )
    engine.set_model(before)
    n3 = ModelUpdate(
        UpdateAction.ADD, (Node("N3", ("m1", "m2"), ("m3",)),), (ModelObserver.make("hz", ["m3"]),)
    )
    engine.update(n3)
    engine.update(ModelUpdate(UpdateAction.REMOVE, n3.nodes, n3.observers))
    assert engine.model == before


def test_observations_of_a_removed_observer_are_forgotten() -> None:
    engine = thesis()
    engine.observe(ObservationInfo("component", ("N4",), -1))
    engine.update(
        ModelUpdate(
            UpdateAction.REMOVE,
            (Node("N4"),),
            (ModelObserver.make("component", ["N4"]), ModelObserver.make("hz", ["m4"])),
        )
    )
    assert engine.diagnose().status is Status.OK


@pytest.mark.parametrize(
    ("update", "reason"),
    [
        (ModelUpdate(UpdateAction.REMOVE, (Node("N9"),)), "unknown node 'N9'"),
        (ModelUpdate(UpdateAction.UPDATE, (Node("N9"),)), "unknown node 'N9'"),
        (
            ModelUpdate(UpdateAction.ADD, (Node("N1", (), ("m1",)),)),
            "node 'N1' is already in the model",
        ),
        (
            ModelUpdate(UpdateAction.ADD, (), (ModelObserver.make("hz", ["m9"]),)),
            "unknown topic 'm9'",
        ),
        (
            ModelUpdate(
                UpdateAction.ADD, (Node("N5", ("q",), ()),), (ModelObserver.make("hz", ["q"]),)
            ),
            "topic 'q' that no node publishes",
        ),
        (
            ModelUpdate(UpdateAction.ADD, (), (ModelObserver.make("component", ["N7"]),)),
            "unknown node 'N7'",
        ),
        (
            ModelUpdate(UpdateAction.ADD, (), (ModelObserver.make("hz", ["m1"]),)),
            r"frequency\[m1\] is already",
        ),
        (ModelUpdate(UpdateAction.REMOVE, (Node("N3"),)), "topic 'm3' that no node publishes"),
        (
            ModelUpdate(UpdateAction.ADD, (), (ModelObserver.make("hz", ["m3"], ["N1"]),)),
            "caller id 'N1' that publishes none of its topics",
        ),
        (
            ModelUpdate(UpdateAction.REMOVE, (), (ModelObserver.make("timeout", ["m3"]),)),
            "is not in the model",
        ),
    ],
    ids=lambda x: x.action.value if isinstance(x, ModelUpdate) else x,
)
def test_an_invalid_update_is_refused_with_its_reason_and_changes_nothing(
    update: ModelUpdate, reason: str
) -> None:
    engine = thesis()
    engine.observe(ObservationInfo("hz", ("m4",), -1))
    before = engine.model
    with pytest.raises(ConfigError, match=reason):
        engine.update(update)
    assert engine.model is before
    assert set(engine.diagnose().diagnoses) == {("N1",), ("N2",), ("N3",), ("N4",)}


@pytest.mark.parametrize(
    ("payload", "reason"),
    [
        ({"action": "ADD", "nodes": [{"name": "ABS", "pub_topic": ["x"]}]}, "starts with 'AB'"),
        ({"action": "ADD", "nodes": [{"name": "n", "pub_topic": ["/ABx"]}]}, "starts with 'AB'"),
        (
            {"action": "ADD", "observers": [{"type": "timing", "resource": ["m1"]}]},
            "watches 2 resources, not 1",
        ),
        (
            {"action": "ADD", "observers": [{"type": "hz", "resource": ["m1", "m2"]}]},
            "watches 1 resources, not 2",
        ),
        (
            {
                "action": "ADD",
                "observers": [{"type": "movement", "resource": ["a", "b", "c", "d"]}],
            },
            "2 or 3 resources",
        ),
        (
            {"action": "ADD", "observers": [{"type": "hertz", "resource": ["m1"]}]},
            "unknown observer type",
        ),
        ({"action": "MERGE"}, "unknown model update action 'MERGE'"),
        ({"action": "ADD", "nodes": {"name": "x"}}, "'nodes' must be a list of objects"),
    ],
)
def test_a_malformed_update_request_is_refused_with_its_reason(
    payload: dict[str, object], reason: str
) -> None:
    with pytest.raises(ConfigError, match=reason):
        ModelUpdate.from_payload(payload)


def test_update_replaces_a_node_and_set_replaces_the_model() -> None:
    engine = thesis()
    engine.update(ModelUpdate(UpdateAction.UPDATE, (Node("N4", ("m3", "m1"), ("m4",)),)))
    node = engine.model.node("N4")
    assert node is not None and node.sub_topic == ("m3", "m1")
    engine.update(
        ModelUpdate(
            UpdateAction.SET, (Node("solo", (), ("x",)),), (ModelObserver.make("hz", ["x"]),)
        )
    )
    assert [n.name for n in engine.model.nodes] == ["solo"]


def test_a_problem_too_large_for_a_template_is_solved_on_its_own() -> None:
    # root feeds 40 topics with one publisher each: 40 conflicts and 41 classes
    width = 40
    nodes = [Node("root", (), ("r",))] + [Node(f"a{i}", ("r",), (f"m{i}",)) for i in range(width)]
    observers = tuple(ModelObserver.make("hz", [f"m{i}"]) for i in range(width))
    engine = DiagnosisEngine(SystemDescription(tuple(nodes), observers))
    for i in range(width):
        engine.observe(ObservationInfo("hz", (f"m{i}",), -1))
    result = engine.diagnose()
    assert result.status is Status.DIAGNOSED
    assert result.diagnoses == (("root",), tuple(sorted(f"a{i}" for i in range(width))))
    engine.observe(ObservationInfo("hz", ("m0",), 0, stamp=1.0))
    engine.max_card = 1
    assert engine.diagnose().diagnoses == (("root",),)


def test_a_time_bound_returns_timeout_with_what_was_found() -> None:
    # a ring: w_i joins the outputs of u_i and u_i+1, which share the root's topic; the
    # failure of every w_i is explained by {root}, and by a vast number of choices of
    # u's and w's around the ring
    width = 60
    nodes = [Node("root", (), ("r",))]
    nodes += [Node(f"u{i}", ("r",), (f"p{i}",)) for i in range(width)]
    nodes += [Node(f"w{i}", (f"p{i}", f"p{(i + 1) % width}"), (f"q{i}",)) for i in range(width)]
    observers = [ModelObserver.make("hz", [f"q{i}"]) for i in range(width)]
    engine = DiagnosisEngine(SystemDescription(tuple(nodes), tuple(observers)), timeout=0.2)
    for i in range(width):
        engine.observe(ObservationInfo("hz", (f"q{i}",), -1))
    result = engine.diagnose()
    assert result.status is Status.TIMEOUT
    assert result.diagnoses[0] == ("root",)
    conflicts = [{"root", f"u{i}", f"u{(i + 1) % width}", f"w{i}"} for i in range(width)]
    for diagnosis in result.diagnoses[1:100]:
        assert all(c & set(diagnosis) for c in conflicts)  # explains every failure
        for name in diagnosis:  # and nothing can be left out
            assert any(c & set(diagnosis) == {name} for c in conflicts)


def test_a_time_bound_keeps_the_smallest_diagnoses_among_very_many() -> None:
    # root feeds 24 topics with two publishers each: {root} explains every failure, and
    # so does each of the 2**24 choices of one publisher per topic
    topics = 24
    nodes = [Node("root", (), ("r",))]
    for i in range(topics):
        nodes += [Node(f"a{i}", ("r",), (f"m{i}",)), Node(f"b{i}", ("r",), (f"m{i}",))]
    observers = tuple(ModelObserver.make("hz", [f"m{i}"]) for i in range(topics))
    engine = DiagnosisEngine(SystemDescription(tuple(nodes), observers), timeout=1.0)
    for i in range(topics):
        engine.observe(ObservationInfo("hz", (f"m{i}",), -1))
    result = engine.diagnose()
    assert result.status is Status.TIMEOUT  # far too many to enumerate in a second
    assert result.diagnoses[0] == ("root",)
    assert all(len(d) == topics for d in result.diagnoses[1:])
