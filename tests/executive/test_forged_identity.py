"""Identity is the login: a component with its own valid login cannot speak for another.

A real executive of the use case makes its access rules from the robot description; the
attacker holds ``take_picture``'s or ``cam``'s login and names itself ``lidar`` or
``move_to``, on the key and in the payload, as a hostile component would.
"""

from __future__ import annotations

import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

from executive.bus import security
from executive.bus.api.monitoring import DIAGNOSIS_MODEL_CHANGE, DIAGNOSIS_MODEL_READ, ModelChange
from executive.bus.keys import RESOURCES
from executive.bus.message import Message
from executive.bus.session import Bus
from executive.testing.harness import RobotProcess, robot_variant
from knowledge.errors import BusError
from tests.conftest import USECASE, wait_for


@pytest.fixture(scope="module")
def robot(tmp_path_factory: pytest.TempPathFactory) -> Iterator[RobotProcess]:
    with RobotProcess(USECASE, tmp_path_factory.mktemp("forged")) as robot:
        yield robot


def component_login(robot: RobotProcess, name: str) -> security.Login:
    login = security.find_login("usecase", security.component_user(name), [robot.folder])
    assert login is not None
    return login


def test_a_component_cannot_publish_as_another_nor_on_topics_it_does_not_publish(
    robot: RobotProcess,
) -> None:
    scans: list[Message] = []
    images: list[Message] = []
    operator = robot.login()
    assert operator is not None
    with Bus("usecase", name="watcher", endpoint=robot.endpoint, login=operator) as watcher:
        watcher.subscribe("topic/scan", scans.append, decoded=False)
        watcher.subscribe("topic/image", images.append, decoded=False)
        cam = component_login(robot, "cam")
        with Bus("usecase", name="lidar", endpoint=robot.endpoint, login=cam) as forger:
            for _ in range(20):  # the flood of the issue, as lidar
                forger.publish("topic/scan", {"ranges": [0.0]})
                forger.publish("topic/image", {"pixels": []})
        picture = component_login(robot, "take_picture")
        with Bus("usecase", name="take_picture", endpoint=robot.endpoint, login=picture) as own:
            own.publish("topic/scan", {"ranges": [0.0]})  # take_picture publishes nothing
        with Bus("usecase", name="cam", endpoint=robot.endpoint, login=cam) as real:
            assert real.wait_for_subscriber("topic/image")
            real.publish("topic/image", {"pixels": [1]})
            assert wait_for(lambda: images)
            time.sleep(0.3)  # the forged ones came earlier, from other sessions: a margin
    assert scans == []
    assert [m.caller_id for m in images] == ["cam"]


def test_a_result_speaks_only_for_the_component_whose_key_it_is_on(robot: RobotProcess) -> None:
    after = robot.events()[-1].id if robot.events() else 0
    forged = {"component": "move_to", "goal_id": "g1", "status": "failed", "value": {}}
    login = component_login(robot, "take_picture")
    with Bus("usecase", name="take_picture", endpoint=robot.endpoint, login=login) as bus:
        assert bus.wait_for_subscriber("component/take_picture/result")
        bus.publish("component/move_to/result", forged)  # another's key: refused
        bus.publish("component/take_picture/result", forged)  # its own, naming another
        bus.publish("component/take_picture/result", {**forged, "component": "take_picture"})
        robot.wait_for_event("GOAL_RESULT_FAILED", "take_picture", after=after)
    results = [e for e in robot.events() if e.id > after and e.kind.startswith("GOAL_RESULT")]
    assert [e.subject for e in results] == ["take_picture"]


def test_an_operator_reads_the_diagnosis_model_but_cannot_blind_it(robot: RobotProcess) -> None:
    before = DIAGNOSIS_MODEL_READ.call(robot.bus)
    assert before.ok and before.model
    with pytest.raises(BusError, match="no answer"):
        DIAGNOSIS_MODEL_CHANGE.call(robot.bus, ModelChange("SET"), timeout=2.0)
    assert DIAGNOSIS_MODEL_READ.call(robot.bus) == before


def test_forgeries_leave_the_executive_running(robot: RobotProcess, tmp_path: Path) -> None:
    assert robot.running
    assert "Traceback" not in robot.log_tail(100_000)


def test_a_host_reports_resources_of_its_own_components_only(tmp_path: Path) -> None:
    placed = {"functionalities": {"cam": {"host": "back"}}}
    description = robot_variant(USECASE, tmp_path / "description", placed)
    with RobotProcess(description, tmp_path) as robot:
        heard: list[dict[str, Any]] = []
        login = security.find_host_login("usecase", "back", robot.folder)
        with Bus("usecase", name="back", endpoint=robot.endpoint, login=login) as host:
            robot.bus.subscribe(RESOURCES, lambda m: heard.append(m.payload))
            nodes = [
                {"name": name, "pid": 1, "hostname": "back", "cpu": 99.0, "memory": 1 << 40}
                for name in ("cam", "lidar")
            ]
            report = {"hostname": "back", "nodes": nodes, "stamp": time.time()}
            assert host.wait_for_subscriber("host/back/resources")
            host.publish(RESOURCES, report)  # not a key a host may publish on
            host.publish("host/back/resources", report)  # lidar is not placed on back
            assert wait_for(lambda: any(p["hostname"] == "back" for p in heard))
            time.sleep(0.3)
        from_back = [p for p in heard if p["hostname"] == "back"]
        assert [[n["name"] for n in p["nodes"]] for p in from_back] == [["cam"]]
