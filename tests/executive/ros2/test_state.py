"""dura's state on ROS 2: what a plain DDS reader of /diagnostics and /dura/events gets."""

from __future__ import annotations

import json
import time
from collections.abc import Iterator
from typing import Any

import pytest
from cyclonedds._clayer import ddspy_take
from cyclonedds.core import InstanceState, SampleState, ViewState
from cyclonedds.sub import DataReader

from executive.bus.keys import DIAGNOSES, EVENTS, OBSERVATIONS
from executive.bus.payloads import TIMEOUT, DiagnosisInfo, ObservationInfo
from executive.bus.service import Context, ServiceState
from executive.ros2.link import Ros2Link
from executive.ros2.state import ERROR, OK, Ros2StatePublisher
from knowledge.errors import ServiceError
from knowledge.ros2_messages import standard_store
from tests.conftest import wait_for
from tests.executive.ros2.messages import DiagnosticArray, String
from tests.executive.ros2.peer import RosPeer

ANY = SampleState.Any | ViewState.Any | InstanceState.Any


@pytest.fixture
def state(context: Context, link: Ros2Link) -> Iterator[Ros2StatePublisher]:
    assert context.robot.ros2 is not None
    service = Ros2StatePublisher(context, context.robot.ros2, link=link, interval=0.05)
    service.configure()
    service.activate()
    try:
        yield service
    finally:
        service.shutdown()


class Heard:
    """Raw samples a plain reader took, kept in order."""

    def __init__(self, reader: DataReader[Any]) -> None:
        self.reader = reader
        self.raw: list[bytes] = []

    def matched(self) -> bool:
        """Whether dura's writer and this reader found each other."""
        return bool(self.reader.get_matched_publications())

    def take(self) -> list[bytes]:
        self.raw += [
            data for data, info in ddspy_take(self.reader._ref, ANY, 64) if info.valid_data
        ]
        return self.raw


def observation(resource: str, number: int, callers: tuple[str, ...] = ()) -> dict[str, Any]:
    info = ObservationInfo("frequency", (resource,), number, "stopped" if number < 0 else "ok",
                           "no message for 2 s", callers, time.time())  # fmt: skip
    return {**info.to_payload(), "values": {"frequency": 0.0}, "observer": "lidar/0"}


def test_observations_and_diagnoses_reach_a_plain_reader_of_diagnostics_as_rosbags_encodes_them(
    context: Context, state: Ros2StatePublisher, peer: RosPeer
) -> None:
    heard = Heard(peer.subscriber("monitor", "/diagnostics", DiagnosticArray))
    assert wait_for(heard.matched)
    context.bus.publish(OBSERVATIONS, observation("scan", TIMEOUT, ("lidar",)))
    context.bus.publish(OBSERVATIONS, observation("odom", 1))
    diagnosis = DiagnosisInfo("DIAGNOSED", (("lidar",), ("lidar_filter", "robot_base")))
    context.bus.publish(DIAGNOSES, diagnosis.to_payload())

    def statuses() -> dict[str, Any]:
        return {
            s.name: s for data in heard.take() for s in DiagnosticArray.deserialize(data).status
        }

    assert wait_for(lambda: len(statuses()) == 3)
    found = statuses()
    scan = found["dura: frequency scan [lidar]"]
    assert (scan.level, scan.message, scan.hardware_id) == (ERROR, "stopped", "lidar/0")
    values = {v.key: v.value for v in scan.values}
    assert values == {"frequency": "0", "observation": "-4", "detail": "no message for 2 s"}
    assert found["dura: frequency odom"].level == OK
    diagnosed = found["dura: diagnosis"]
    assert (diagnosed.level, diagnosed.message) == (ERROR, "faulty: lidar (or 1 other diagnoses)")
    assert {v.key: v.value for v in diagnosed.values}["diagnosis 2"] == "lidar_filter, robot_base"

    store = standard_store("jazzy")
    name = "diagnostic_msgs/msg/DiagnosticArray"
    for data in heard.raw:
        reference = bytes(store.serialize_cdr(store.deserialize_cdr(data, name), name))
        assert data[: len(reference)] == reference
        assert set(data[len(reference) :]) <= {0} and len(data) - len(reference) < 4  # padding


def state_nodes(state: Ros2StatePublisher) -> dict[str, Any]:
    link = state._link
    assert link is not None
    return link.discovery.nodes()


def test_executive_events_are_json_strings_on_dura_events(
    context: Context, state: Ros2StatePublisher, peer: RosPeer
) -> None:
    heard = Heard(peer.subscriber("monitor", "/dura/events", String))
    assert wait_for(heard.matched)
    assert state_nodes(state)["/dura"].publishes == ("/diagnostics", "/dura/events")
    event = {"id": 7, "stamp": 12.5, "kind": "GOAL_ADDED", "subject": "g1", "data": {"x": 1}}
    context.bus.publish(EVENTS, event)
    assert wait_for(heard.take)
    assert json.loads(String.deserialize(heard.raw[0]).data) == event


def test_the_service_opens_and_closes_a_link_of_its_own_when_given_none(
    context: Context, domain: int, peer: RosPeer
) -> None:
    assert context.robot.ros2 is not None
    service = Ros2StatePublisher(context, context.robot.ros2)
    service.configure()
    service.activate()
    heard = Heard(peer.subscriber("monitor", "/dura/events", String))
    try:
        assert wait_for(heard.matched)
        context.bus.publish(EVENTS, {"id": 1, "kind": "EXECUTIVE_STARTED"})
        assert wait_for(heard.take)
    finally:
        service.shutdown()
    assert service.state is ServiceState.FINALIZED
    with pytest.raises(ServiceError, match="cannot shutdown while finalized"):
        service.shutdown()  # refused: a service shuts down once
