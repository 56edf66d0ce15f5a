"""Anything on the DDS domain may publish on /dura/goals: every value is answered once,
nothing is stored, and a flood is answered ``busy`` rather than left silent.

A real ``dura run`` of the patrol robot of examples/ros2, real Cyclone DDS participants.
"""

from __future__ import annotations

import json
import queue
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

from executive.ros2.names import dds_topic
from executive.ros2.participant import Participant
from executive.ros2.qos import dds_qos
from executive.testing.harness import RobotProcess, robot_variant
from knowledge.ros2_spec import QosProfile
from tests.conftest import wait_for
from tests.executive.ros2.test_robot import EXAMPLE, RosUser

pytestmark = pytest.mark.slow

STRING = "std_msgs/msg/String"
VALID = json.dumps({"expression": "(visited lab)"})
HOSTILE = [
    '{"expression": "(visited lab)", "priority": Infinity}',
    '{"expression": "(visited lab)", "deadline": NaN}',
    '{"expression": "(visited lab)", "deadline": 1e308}',
    '{"expression": "(visited lab)", "priority": 1e400}',
    '{"expression": "(visited lab)", "priority": ' + "[" * 50_000 + "]" * 50_000 + "}",
    '{"expression": 5}',
    '{"expression": "(visited lab)", "priority": "high"}',
    '{"expression": "(visited lab)", "priority": true}',
    '{"expression": "(visited lab)", "deadline": -1}',
    "[1, 2]",
    '{"expression": "(visited ' + "x" * 900_000 + ')"}',
    "(visited " + "lob" * 3_000 + ")",
    "x" * 200_000,
    "{",
]


@pytest.fixture(scope="module")
def patrol(domain: int, tmp_path_factory: pytest.TempPathFactory) -> Iterator[RobotProcess]:
    folder = tmp_path_factory.mktemp("hostile-goals")
    description = robot_variant(EXAMPLE, folder / "robot", {"ros2": {"domain_id": domain}})
    with RobotProcess(description, folder / "run") as robot:
        yield robot


def test_every_hostile_goal_gets_one_short_reply_and_nothing_is_stored(
    patrol: RobotProcess, domain: int
) -> None:
    with Participant(domain, name="hostile") as participant:
        user = RosUser(participant)
        for text in HOSTILE:
            reply = user.submit(text)
            assert reply["accepted"] is False, (text[:80], reply)
            assert len(json.dumps(reply)) < 1000, (text[:80], len(json.dumps(reply)))
        assert patrol.goals() == []  # nothing stored
        accepted = user.submit(VALID)  # the goal thread lives on
        assert accepted["accepted"] is True, accepted
    assert user.replies.empty()  # one reply each, no more
    assert "Traceback" not in patrol.log_tail(100_000)


def test_a_flood_is_answered_busy_and_the_topic_still_takes_goals(
    patrol: RobotProcess, domain: int, tmp_path: Path
) -> None:
    with Participant(domain, name="flood") as participant:
        user = RosUser(participant)
        every: queue.Queue[dict[str, Any]] = queue.Queue()  # the replies, none lost here
        decode = user.library.decoder(STRING)

        def replied(samples: list[Any], received: float) -> None:
            for data, info in samples:
                if info.valid_data:
                    every.put(json.loads(decode(data)["data"]))

        string = user.library.idl(STRING)
        keep_all = dds_qos(QosProfile(history="keep_all"))
        participant.reader(dds_topic("/dura/goals/replies"), string, keep_all, replied)
        assert wait_for(lambda: user.goals.matched() > 0, timeout=20)
        sent = 2_000
        for i in range(sent):
            data = {"data": f"(visited lob{i})"}  # refused: nothing stored either way
            user.goals.write(user.library.create(STRING, data))
        replies: list[dict[str, Any]] = []

        def answered() -> bool:
            while True:
                try:
                    replies.append(every.get_nowait())
                except queue.Empty:
                    return any("busy" in r["reason"] for r in replies) and len(replies) >= 100

        assert wait_for(answered, timeout=60), replies[-3:]
        assert all(r["accepted"] is False for r in replies)
    with Participant(domain, name="afterwards") as participant:
        after = RosUser(participant)
        reply = after.submit(json.dumps({"expression": "(visited office)"}))
        while "busy" in reply.get("reason", "") or "lob" in reply.get("expression", ""):
            reply = after.replies.get(timeout=60)  # the flood's last answers come first
        assert reply["accepted"] is True, reply
