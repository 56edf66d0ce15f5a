"""The bus is not open: only the robot's users connect, and each may do only its part."""

from __future__ import annotations

import stat
import time
from collections.abc import Iterator
from pathlib import Path
from unittest.mock import ANY

import pytest
import zenoh

from executive.bus import security
from executive.bus.api.components import COMPONENT_ACHIEVE, Achievement
from executive.bus.message import Message
from executive.bus.security import Credentials, Login
from executive.bus.session import Bus, session_config
from executive.bus.verb import Empty
from knowledge.errors import BusError
from knowledge.robot import load_robot
from tests.conftest import wait_for
from tests.knowledge.robot_cases import BrokenRobot

ROBOT = "guarded"
COMPONENTS = ("lidar", "cam")
TOPICS = {  # as a robot description would list them
    "lidar": security.Topics(publishes=("scan",), subscribes=("cmd_vel",)),
    "cam": security.Topics(publishes=("image",), subscribes=("scan",), may_subscribe=("diag/**",)),
}


@pytest.fixture
def credentials(tmp_path: Path) -> Credentials:
    return security.ensure_credentials(tmp_path / "bus.json", ROBOT, COMPONENTS)


@pytest.fixture
def router(tmp_path: Path, endpoint: str, credentials: Credentials) -> Iterator[Bus]:
    with Bus(
        ROBOT,
        name="executive",
        endpoint=endpoint,
        listen=True,
        login=credentials.login(security.EXECUTIVE),
        dictionary=security.dictionary(credentials, tmp_path / "users"),
        access=security.access_control(ROBOT, COMPONENTS, topics=TOPICS),
    ) as bus:
        yield bus


def heard(router: Bus, key: str) -> list[Message]:
    got: list[Message] = []
    router.subscribe(key, got.append, decoded=False)
    return got


def test_credentials_are_made_once_for_the_owner_only_and_grow_with_the_robot(
    tmp_path: Path,
) -> None:
    path = tmp_path / ".dura" / "robot.bus.json"
    first = security.ensure_credentials(path, "robot", ["lidar"])
    assert stat.S_IMODE(path.stat().st_mode) == 0o600
    assert set(first.passwords) == {"executive", "service", "operator", "fleet", "component.lidar"}
    again = security.ensure_credentials(path, "robot", ["lidar", "cam"])
    assert again.passwords["operator"] == first.passwords["operator"]
    assert "component.cam" in again.passwords
    path.chmod(0o644)
    with pytest.raises(BusError, match="others may read the bus credentials"):
        security.read_credentials(path)


def test_a_client_without_the_robots_credentials_cannot_connect(
    router: Bus, endpoint: str, credentials: Credentials
) -> None:
    with pytest.raises(BusError, match="no executive for robot 'guarded'"):
        Bus(ROBOT, name="intruder", endpoint=endpoint)
    wrong = Login(security.OPERATOR, "guess")
    with pytest.raises(BusError, match="refused these credentials"):
        Bus(ROBOT, name="intruder", endpoint=endpoint, login=wrong)


def test_an_operator_asks_but_cannot_forge_what_services_publish(
    router: Bus, endpoint: str, credentials: Credentials
) -> None:
    router.serve("executive/api/status", lambda request: {"robot": ROBOT})
    diagnoses = heard(router, "diagnoses")
    with Bus(
        ROBOT, name="cli", endpoint=endpoint, login=credentials.login(security.OPERATOR)
    ) as operator:
        assert operator.request("executive/api/status") == {"robot": ROBOT}
        assert operator.wait_for_subscriber("diagnoses")  # what it publishes leaves it
        operator.publish("diagnoses", {"status": "DIAGNOSED", "diagnoses": [["lidar"]]})
        router.publish("diagnoses", {"status": "OK", "diagnoses": []})  # the real one arrives
        assert wait_for(lambda: len(diagnoses) >= 1)
        # nothing tells that a message was refused: give the forged one the time it
        # would take to arrive (it comes from another session than the real one)
        time.sleep(0.3)
    assert [m.payload["status"] for m in diagnoses] == ["OK"]


def test_a_component_publishes_topics_and_its_own_results_only(
    router: Bus, endpoint: str, credentials: Credentials
) -> None:
    results = heard(router, "component/*/result")
    scans = heard(router, "topic/scan")
    login = credentials.login(security.component_user("lidar"))
    with Bus(ROBOT, name="lidar", endpoint=endpoint, login=login) as lidar:
        for key in ("topic/scan", "component/cam/result", "component/lidar/result"):
            assert lidar.wait_for_subscriber(key)  # what it publishes leaves it
        lidar.publish("topic/scan", {"ranges": [1.0]})
        lidar.publish("component/cam/result", {"forged": True})
        lidar.publish("component/lidar/result", {"own": True})
        # from one session to one subscriber in order: a forged result let through
        # would come before its own
        assert wait_for(lambda: scans and any(m.key == "component/lidar/result" for m in results))
    assert [m.key for m in results] == ["component/lidar/result"]
    assert len(scans) == 1


def test_the_caller_id_of_a_topic_is_the_login_that_sent_it(
    router: Bus, endpoint: str, credentials: Credentials
) -> None:
    scans = heard(router, "topic/scan")
    images = heard(router, "topic/image")
    cam_login = credentials.login(security.component_user("cam"))
    # the cam's login names itself lidar: on a topic lidar publishes, and on its own
    with Bus(ROBOT, name="lidar", endpoint=endpoint, login=cam_login) as forger:
        assert forger.wait_for_subscriber("topic/scan")
        for _ in range(5):
            forger.publish("topic/scan", {"forged": True})
            forger.publish("topic/image", {"forged": True})
    # the same, written by hand: the key of another sender, the attachment of another
    prefix = f"dura/{ROBOT}/"
    with zenoh.open(session_config(connect=(endpoint,), login=cam_login)) as session:
        for key in ("from/lidar/topic/scan", "from/lidar/topic/image", "topic/scan"):
            session.put(prefix + key, b'{"forged": true}', attachment=b"lidar")
    lidar_login = credentials.login(security.component_user("lidar"))
    with (
        Bus(ROBOT, name="cam", endpoint=endpoint, login=cam_login) as cam,
        Bus(ROBOT, name="lidar", endpoint=endpoint, login=lidar_login) as lidar,
    ):
        cam.publish("topic/scan", {"forged": True})  # not a topic cam publishes
        cam.publish("topic/image", {"own": True})
        lidar.publish("topic/scan", {"own": True})
        assert wait_for(lambda: scans and images)
        time.sleep(0.3)  # the forged ones came first, from other sessions: a margin
    assert [(m.caller_id, m.payload) for m in scans] == [("lidar", {"own": True, "stamp": ANY})]
    assert [(m.caller_id, m.payload) for m in images] == [("cam", {"own": True, "stamp": ANY})]


def test_a_component_hears_only_the_topics_it_subscribes(
    router: Bus, endpoint: str, credentials: Credentials
) -> None:
    got: list[Message] = []
    login = credentials.login(security.component_user("lidar"))
    with Bus(ROBOT, name="lidar", endpoint=endpoint, login=login) as lidar:
        lidar.subscribe("topic/image", got.append)  # cam's pictures: not for lidar
        lidar.subscribe("topic/cmd_vel", got.append)
        assert router.wait_for_subscriber("topic/cmd_vel")
        router.publish("topic/image", {"picture": 1})
        router.publish("topic/cmd_vel", {"v": 1.0})  # after the picture, to the same session
        assert wait_for(lambda: got)
        time.sleep(0.2)
    assert [m.key for m in got] == ["topic/cmd_vel"]


def test_the_description_may_open_more_topics_to_a_component(
    router: Bus, endpoint: str, credentials: Credentials
) -> None:
    """cam's ``may_subscribe: [diag/**]`` opens every topic under diag, and only to cam."""
    got: dict[str, list[str]] = {"lidar": [], "cam": []}
    logins = {name: credentials.login(security.component_user(name)) for name in got}
    with (
        Bus(ROBOT, name="lidar", endpoint=endpoint, login=logins["lidar"]) as lidar,
        Bus(ROBOT, name="cam", endpoint=endpoint, login=logins["cam"]) as cam,
    ):
        for name, bus in (("lidar", lidar), ("cam", cam)):
            for topic in ("topic/diag/cpu", "topic/diag/motors/left", "topic/image"):
                bus.subscribe(topic, lambda m, n=name: got[n].append(m.key))
        lidar.subscribe("topic/cmd_vel", lambda m: got["lidar"].append(m.key))
        cam.subscribe("topic/scan", lambda m: got["cam"].append(m.key))
        assert router.wait_for_subscriber("topic/cmd_vel")
        assert router.wait_for_subscriber("topic/scan")
        for topic in ("diag/cpu", "diag/motors/left", "image", "cmd_vel", "scan"):
            router.publish(f"topic/{topic}", {"n": 1})  # in order, to each session
        assert wait_for(lambda: got["lidar"] and len(got["cam"]) >= 3)
        time.sleep(0.2)
    assert got["lidar"] == ["topic/cmd_vel"]
    assert sorted(got["cam"]) == ["topic/diag/cpu", "topic/diag/motors/left", "topic/scan"]


def test_a_description_opens_more_topics_with_may_subscribe(tmp_path: Path) -> None:
    opened = "publishes: [image]\n    may_subscribe: [odom, '**']"
    path = BrokenRobot("", "publishes: [image]", opened, "", "").write(tmp_path)
    topics = security.topics_of(load_robot(path))
    assert topics["cam"].may_subscribe == ("odom", "**")
    assert [n for n, t in topics.items() if t.may_subscribe] == ["cam"]
    rules = security.access_control("usecase", ["cam"], topics=topics)["rules"]
    heard = next(r for r in rules if r["id"] == "own cam subscribes")
    assert heard["key_exprs"] == [
        "dura/usecase/from/*/topic/odom",
        "dura/usecase/from/*/topic/**",
    ]


def test_a_component_stores_achievements_for_itself_only(
    router: Bus, endpoint: str, credentials: Credentials
) -> None:
    stored: list[Achievement] = []

    def store(achievement: Achievement) -> Empty:
        stored.append(achievement)
        return Empty()

    COMPONENT_ACHIEVE.serve(router, store)
    login = credentials.login(security.component_user("lidar"))
    with Bus(ROBOT, name="lidar", endpoint=endpoint, login=login) as lidar:
        COMPONENT_ACHIEVE.call(lidar, Achievement("cam", "pose", 1))  # names another
    with (
        Bus(ROBOT, name="cam", endpoint=endpoint, login=login) as forger,
        pytest.raises(BusError, match="no answer"),  # asks under another's name
    ):
        COMPONENT_ACHIEVE.call(forger, Achievement("cam", "pose", 2), timeout=1.0)
    assert stored == [Achievement("lidar", "pose", 1)]


def test_a_fleet_asks_for_steps_and_hears_them_but_posts_no_goal(
    router: Bus, endpoint: str, credentials: Credentials
) -> None:
    router.serve("executive/steps/run", lambda request: {})
    router.serve("executive/api/goal/add", lambda request: {"id": 1})
    with Bus(
        ROBOT, name="fleet.depot", endpoint=endpoint, login=credentials.login(security.FLEET)
    ) as fleet:
        progress: list[Message] = []
        fleet.subscribe("executive/steps/progress", progress.append)
        assert fleet.request("executive/steps/run") == {}
        assert wait_for(lambda: router.wait_for_subscriber("executive/steps/progress"))
        router.publish("executive/steps/progress", {"run": "a", "progress": "started"})
        assert wait_for(lambda: len(progress) == 1)
        with pytest.raises(BusError, match="no answer"):
            fleet.request("executive/api/goal/add", timeout=1.0)


def test_the_executive_writes_the_fleets_login_alone_for_the_owner_only(
    tmp_path: Path, credentials: Credentials
) -> None:
    security.write_fleet_credentials(credentials, tmp_path)
    path = security.fleet_credentials_file(tmp_path, ROBOT)
    assert stat.S_IMODE(path.stat().st_mode) == 0o600
    written = security.read_credentials(path)
    assert dict(written.passwords) == {"fleet": credentials.passwords["fleet"]}


def test_a_session_is_a_components_when_its_login_is(
    router: Bus, endpoint: str, credentials: Credentials
) -> None:
    assert not router.component
    with Bus(ROBOT, name="cli", endpoint=endpoint,
             login=credentials.login(security.OPERATOR)) as cli:  # fmt: skip
        assert not cli.component
    login = credentials.login(security.component_user("lidar"))
    with Bus(ROBOT, name="lidar", endpoint=endpoint, login=login) as lidar:
        assert lidar.component
