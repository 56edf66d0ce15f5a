"""The diagnosis service on a real bus: model updates, observations, diagnoses."""

from __future__ import annotations

import threading
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

from executive.bus.api.monitoring import DIAGNOSIS_EXONERATE, ExonerationChange
from executive.bus.keys import DIAGNOSES, DIAGNOSIS_MODEL, OBSERVATIONS
from executive.bus.message import Message
from executive.bus.payloads import DiagnosisInfo
from executive.bus.service import Context
from executive.bus.session import Bus
from knowledge.knowledge_base import KnowledgeBase
from knowledge.robot import load_robot
from monitoring.diagnosis.diagnosis_service import DiagnosisService
from tests.conftest import USECASE
from tests.monitoring.diagnosis.cases import THESIS_NODES, THESIS_OBSERVERS


class Peer:
    """A client on the bus that collects diagnoses."""

    def __init__(self, bus: Bus) -> None:
        self.bus = bus
        self.received: list[DiagnosisInfo] = []
        self.arrived = threading.Condition()
        bus.subscribe(DIAGNOSES, self._on)

    def _on(self, message: Message) -> None:
        with self.arrived:
            self.received.append(DiagnosisInfo.from_payload(message.payload))
            self.arrived.notify_all()

    def wait_for(
        self, status: str, diagnoses: list[list[str]] | None = None, timeout: float = 10.0
    ) -> DiagnosisInfo:
        deadline = time.monotonic() + timeout
        with self.arrived:
            while True:
                for info in reversed(self.received):
                    if info.status == status and (
                        diagnoses is None or [list(d) for d in info.diagnoses] == diagnoses
                    ):
                        return info
                left = deadline - time.monotonic()
                assert left > 0, f"no {status} {diagnoses} in {self.received}"
                self.arrived.wait(left)

    def forget(self) -> None:
        """Forget the diagnoses received so far."""
        with self.arrived:
            self.received.clear()

    def observe(self, kind: str, resource: list[str], value: int, stamp: float) -> None:
        self.bus.publish(
            OBSERVATIONS, {"type": kind, "resource": resource, "observation": value, "stamp": stamp}
        )


@pytest.fixture
def running(endpoint: str, tmp_path: Path) -> Iterator[tuple[DiagnosisService, Peer]]:
    robot = load_robot(USECASE)
    with (
        Bus(robot.name, name="executive", endpoint=endpoint, listen=True) as bus,
        KnowledgeBase(tmp_path / "kb.db") as kb,
        Bus(robot.name, name="tester", endpoint=endpoint) as client,
    ):
        service = DiagnosisService(Context(robot, bus, kb), period=0.2)
        service.configure()
        service.activate()
        try:
            yield service, Peer(client)
        finally:
            service.shutdown()


def add_thesis_model(peer: Peer) -> dict[str, Any]:
    return peer.bus.request(
        DIAGNOSIS_MODEL,
        {
            "action": "ADD",
            "nodes": [
                {"name": n, "sub_topic": list(s), "pub_topic": list(p)} for n, s, p in THESIS_NODES
            ],
            "observers": [{"type": t, "resource": list(r)} for t, r, _ in THESIS_OBSERVERS],
        },
    )


def test_a_failed_observation_is_diagnosed_and_its_recovery_gives_the_all_clear(
    running: tuple[DiagnosisService, Peer],
) -> None:
    _, peer = running
    assert add_thesis_model(peer)["ok"] is True
    peer.observe("hz", ["m3"], -1, 1.0)
    peer.wait_for("DIAGNOSED", [["N1"], ["N2"], ["N3"]])
    peer.observe("hz", ["m3"], 0, 2.0)
    peer.wait_for("OK", [])


def test_a_faulty_result_is_repeated_for_the_rules_to_count(
    running: tuple[DiagnosisService, Peer],
) -> None:
    _, peer = running
    add_thesis_model(peer)
    peer.observe("component", ["N4"], -1, 1.0)
    peer.wait_for("DIAGNOSED", [["N4"]])
    deadline = time.monotonic() + 10
    while sum(i.status == "DIAGNOSED" for i in peer.received) < 3:
        assert time.monotonic() < deadline
        time.sleep(0.05)


def test_a_refused_model_update_answers_with_the_reason_and_keeps_the_model(
    running: tuple[DiagnosisService, Peer],
) -> None:
    service, peer = running
    add_thesis_model(peer)
    before = service.engine.model
    reply = peer.bus.request(
        DIAGNOSIS_MODEL, {"action": "ADD", "nodes": [{"name": "ABx", "pub_topic": ["q"]}]}
    )
    assert reply == {
        "ok": False,
        "error": "node name 'ABx' starts with 'AB' (reserved for the diagnosis)",
    }
    reply = peer.bus.request(DIAGNOSIS_MODEL, {"action": "REMOVE", "nodes": [{"name": "N3"}]})
    assert reply["ok"] is False and "m3" in reply["error"]
    assert service.engine.model is before
    assert peer.bus.request(DIAGNOSIS_MODEL, {"action": "GET"})["model"] == before.to_payload()


def test_unknown_and_malformed_observations_are_ignored_without_stopping_the_service(
    running: tuple[DiagnosisService, Peer],
) -> None:
    _, peer = running
    add_thesis_model(peer)
    peer.observe("hertz", ["m3"], -1, 1.0)
    peer.observe("timeout", ["nowhere"], -1, 1.0)
    peer.bus.publish(OBSERVATIONS, {"type": "hz"})
    peer.bus.publish_raw(OBSERVATIONS, b"not json")
    peer.observe("hz", ["m4"], -1, 1.0)
    peer.wait_for("DIAGNOSED", [["N1"], ["N2"], ["N3"], ["N4"]])


def test_a_model_change_is_rediagnosed(running: tuple[DiagnosisService, Peer]) -> None:
    _, peer = running
    add_thesis_model(peer)
    peer.observe("hz", ["m4"], -1, 1.0)
    peer.wait_for("DIAGNOSED", [["N1"], ["N2"], ["N3"], ["N4"]])
    reply = peer.bus.request(
        DIAGNOSIS_MODEL,
        {"action": "UPDATE", "nodes": [{"name": "N4", "sub_topic": [], "pub_topic": ["m4"]}]},
    )
    assert reply["ok"] is True
    peer.wait_for("DIAGNOSED", [["N4"]])


def test_exoneration_switched_at_run_time_diagnoses_again_at_once_and_is_logged(
    running: tuple[DiagnosisService, Peer],
) -> None:
    service, peer = running
    add_thesis_model(peer)
    peer.observe("frequency", ["m3"], -1, 1.0)
    peer.observe("frequency", ["m1"], 0, 1.0)
    peer.wait_for("DIAGNOSED", [["N1"], ["N2"], ["N3"]])
    assert DIAGNOSIS_EXONERATE.call(peer.bus, ExonerationChange()).on is False
    peer.forget()  # from here on, only what the switch brings
    assert DIAGNOSIS_EXONERATE.call(peer.bus, ExonerationChange(True)).on is True
    peer.wait_for("DIAGNOSED", [["N2"], ["N3"]])  # m1 is OK: N1 is cleared
    assert DIAGNOSIS_EXONERATE.call(peer.bus, ExonerationChange()).on is True
    peer.forget()
    assert DIAGNOSIS_EXONERATE.call(peer.bus, ExonerationChange(False)).on is False
    peer.wait_for("DIAGNOSED", [["N1"], ["N2"], ["N3"]])
    logged = [e.data for e in service.context.kb.events(kind="EXONERATION")]
    assert logged == [{"on": True}, {"on": False}]
