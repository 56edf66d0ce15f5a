"""The rows of the reliability benchmark about trust (issue 29): an attacker with a
foothold tries, and every try must be refused or survived.

- forged identities: a component's valid login publishing as another component, on
  topics it does not publish, with results and achievements naming another, and the
  operator's login emptying the diagnosis model; refused means nothing of it arrived
  where it would count (an operator's subscriber on ``topic/**``, the event log, the
  model);
- hostile ROS 2 goals: values of every kind on ``/dura/goals`` from a real Cyclone DDS
  participant; survived means one short reply and nothing stored;
- dashboard requests without credentials: from loopback, with guessed tokens and
  passwords, and renamed (DNS rebinding) with a valid cookie; refused means a 401 or 421.
"""

from __future__ import annotations

import base64
import http.client
import itertools
import json
import os
import random
import time
from pathlib import Path

import zenoh

from executive.bus import security
from executive.bus.api.monitoring import DIAGNOSIS_MODEL_CHANGE, DIAGNOSIS_MODEL_READ, ModelChange
from executive.bus.message import Message
from executive.bus.session import Bus, session_config
from executive.testing.harness import RobotProcess, robot_variant
from knowledge.errors import DuraError
from tests.conftest import USECASE, wait_for


def _login(robot: RobotProcess, user: str) -> security.Login:
    login = security.find_login(robot.robot.name, user, [robot.folder])
    assert login is not None
    return login


def forged_identities(count: int, folder: Path) -> tuple[int, int, str]:
    """``(refused, tried, detail)`` of ``count`` forgeries of six kinds."""
    heard: list[Message] = []
    kinds = itertools.cycle(["as lidar", "raw key", "unlisted topic", "result", "achieve",
                             "model"])  # fmt: skip
    tried = refused = 0
    with RobotProcess(USECASE, folder) as robot:
        prefix = f"dura/{robot.robot.name}/"
        cam, picture = _login(robot, "component.cam"), _login(robot, "component.take_picture")
        robot.bus.subscribe("topic/**", heard.append, decoded=False)
        before = len(robot.events())
        model = DIAGNOSIS_MODEL_READ.call(robot.bus)
        with (
            Bus("usecase", name="lidar", endpoint=robot.endpoint, login=cam) as as_lidar,
            Bus("usecase", name="take_picture", endpoint=robot.endpoint, login=picture) as own,
            zenoh.open(session_config(connect=(robot.endpoint,), login=cam)) as raw,
        ):
            for kind in itertools.islice(kinds, count):
                tried += 1
                if kind == "as lidar":
                    as_lidar.publish("topic/scan", {"ranges": [0.0]})
                elif kind == "raw key":
                    raw.put(prefix + "from/lidar/topic/scan", b'{"ranges": [0.0]}')
                elif kind == "unlisted topic":
                    own.publish("topic/scan", {"ranges": [0.0]})
                elif kind == "result":
                    own.publish("component/take_picture/result", {"component": "move_to",
                                "goal_id": "x", "status": "failed", "value": {}})  # fmt: skip
                elif kind == "achieve":
                    replies = raw.get(prefix + "executive/api/component/achieve/move_to",
                                      payload=b'{"component": "move_to", "key": "k"}',
                                      timeout=1.0)  # fmt: skip
                    refused += not any(r.ok is not None for r in replies)
                    continue
                else:
                    try:
                        DIAGNOSIS_MODEL_CHANGE.call(robot.bus, ModelChange("SET"), timeout=1.0)
                    except DuraError:
                        refused += DIAGNOSIS_MODEL_READ.call(robot.bus) == model
                    continue
                refused += 1  # counted back below if it arrived
            real = Bus("usecase", name="cam", endpoint=robot.endpoint, login=cam)
            with real:
                real.publish("topic/image", {"pixels": [1]})  # the sentinel: after them all
                wait_for(lambda: any(m.key == "topic/image" for m in heard), 10)
                time.sleep(0.5)  # the forged ones came from other sessions: a margin
        arrived = [m for m in heard if m.key == "topic/scan"]
        results = [e for e in robot.events()[before:] if e.kind.startswith("GOAL_RESULT")]
        refused -= len(arrived) + len(results)
    return refused, tried, f"{len(arrived)} forged topic messages, {len(results)} results arrived"


HOSTILE_GOALS = [
    '{"expression": "(visited lab)", "priority": Infinity}',
    '{"expression": "(visited lab)", "deadline": NaN}',
    '{"expression": "(visited lab)", "deadline": 1e308}',
    '{"expression": "(visited lab)", "priority": ' + "[" * 50_000 + "]" * 50_000 + "}",
    '{"expression": 5}',
    '{"expression": "(visited lab)", "priority": "high"}',
    "[1, 2]",
    '{"expression": "(visited ' + "x" * 900_000 + ')"}',
    "(visited " + "lob" * 3_000 + ")",
    "{",
]


def hostile_ros2_goals(count: int, folder: Path) -> tuple[int, int, str]:
    """``(survived, tried, detail)``: each answered once, briefly, nothing stored."""
    from executive.ros2.participant import Participant
    from tests.executive.ros2.peer import LOOPBACK
    from tests.executive.ros2.test_robot import EXAMPLE, RosUser

    config = folder / "cyclonedds.xml"
    folder.mkdir(parents=True, exist_ok=True)
    config.write_text(LOOPBACK)
    os.environ["CYCLONEDDS_URI"] = config.as_uri()
    domain = random.SystemRandom().randint(1, 230)
    description = robot_variant(EXAMPLE, folder / "robot", {"ros2": {"domain_id": domain}})
    survived = busy = longest = 0
    with RobotProcess(description, folder / "run") as robot, Participant(domain) as participant:
        user = RosUser(participant)
        for text in itertools.islice(itertools.cycle(HOSTILE_GOALS), count):
            time.sleep(0.1)  # within the rate one publisher may submit at: each one is read
            reply = user.submit(text)
            size = len(json.dumps(reply))
            longest = max(longest, size)
            busy += "busy" in reply["reason"]
            survived += reply["accepted"] is False and size < 1000
        stored = len(robot.goals())
        time.sleep(0.1)
        alive = user.submit('{"expression": "(visited lab)"}')["accepted"] is True
    survived = survived if stored == 0 and alive else 0
    detail = f"longest reply {longest} B, {busy} busy, stored {stored}, a goal after: {alive}"
    return survived, count, detail


def dashboard_without_credentials(count: int, folder: Path) -> tuple[int, int, str]:
    """``(refused, tried, detail)`` of requests without the operator's credentials."""
    from executive.dashboard.server import Dashboard

    anywhere = "0.0.0.0"  # noqa: S104 - every interface, as a robot's dashboard may listen
    guessed = base64.b64encode(b"operator:guess").decode()
    statuses: dict[int, int] = {}
    refused = 0
    with (
        RobotProcess(USECASE, folder) as robot,
        Dashboard.connect(robot.robot, robot.endpoint, port=0, folders=[robot.folder]) as page,
        Dashboard.connect(robot.robot, robot.endpoint, host=anywhere, port=0,
                          folders=[robot.folder]) as wide,
    ):  # fmt: skip
        cookie = f"dura_dashboard={wide.access.token}"
        goal = json.dumps({"expression": "(picture_taken lab)"})
        tries: list[tuple[int, str, str, str, dict[str, str]]] = [
            (page.port, "GET", "/", "127.0.0.1", {}),
            (page.port, "GET", "/api/stream", "localhost", {}),
            (page.port, "POST", "/api/goals", "127.0.0.1", {}),
            (page.port, "POST", "/api/goals/1/cancel", "127.0.0.1", {}),
            (page.port, "GET", "/?token=0123456789abcdef", "127.0.0.1", {}),
            (page.port, "POST", "/api/goals", "127.0.0.1", {"Authorization": f"Basic {guessed}"}),
            (wide.port, "POST", "/api/goals", "attacker.example", {"Cookie": cookie}),
            (wide.port, "GET", "/", "attacker.example:8470", {"Cookie": cookie}),
        ]
        for port, method, path, host, headers in itertools.islice(itertools.cycle(tries), count):
            connection = http.client.HTTPConnection("127.0.0.1", port, timeout=10)
            body = goal if method == "POST" else None
            sent = {"Host": host, "Content-Type": "application/json", **headers}
            connection.request(method, path, body=body, headers=sent)
            response = connection.getresponse()
            response.read()
            connection.close()
            statuses[response.status] = statuses.get(response.status, 0) + 1
            refused += response.status in (401, 421)
        stored = len(robot.goals())
    refused = refused if stored == 0 else 0
    answers = ", ".join(f"{n}× {s}" for s, n in sorted(statuses.items()))
    return refused, count, f"{answers}; goals stored {stored}"
