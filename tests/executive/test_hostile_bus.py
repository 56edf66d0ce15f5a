"""Malformed and forged messages never break the executive or a reader of its state.

The bus is closed to strangers (tests/executive/bus/test_security.py); this sends, with
a trusted service's credentials, what a buggy or hostile peer could: payloads that are
not JSON objects, numbers out of range, nesting too deep to read, 5 MB messages, and
requests of the wrong shape to every verb. The executive answers errors, keeps going,
and logs one line per problem (no traceback); ``dura status`` still reads its state.
"""

from __future__ import annotations

import json
import time
from collections.abc import Iterator
from pathlib import Path

import pytest
import zenoh

from executive.bus import security
from executive.bus.api import components, monitoring, planning, tasks
from executive.bus.keys import DIAGNOSES
from executive.bus.reports import DiagnosisInfo
from executive.bus.session import Bus, session_config
from executive.bus.verb import Verb
from executive.testing.harness import RobotProcess
from tests.conftest import USECASE, run_dura

GARBAGE = [
    b"not json",
    b"[1, 2, 3]",
    b'"a string"',
    b'{"status": "DIAGNOSED", "diagnoses": [[{"a": 1}]]}',
    b'{"value": 1e400, "stamp": 1e400, "state": "ready", "component": "lidar"}',
    b"[" * 100_000 + b"]" * 100_000,
    b'{"pad": "' + b"x" * (5 << 20) + b'"}',
    b'{"component": "lidar", "state": "exploded", "pid": "many"}',
    b'{"type": "hz", "resource": 7, "observation": "bad"}',
]
KEYS = [
    "observations",
    "diagnoses",
    "resources",
    "component/lidar/state",
    "component/move_to/result",
    "component/move_to/feedback",
    "topic/scan",
]
UNHEARD = {"resources"}  # nobody listens to it while no observer of resources runs
VERBS: list[Verb] = [  # type: ignore[type-arg]
    v
    for module in (planning, tasks, components, monitoring)
    for v in vars(module).values()
    if isinstance(v, Verb)
]


@pytest.fixture(scope="module")
def robot(tmp_path_factory: pytest.TempPathFactory) -> Iterator[RobotProcess]:
    with RobotProcess(USECASE, tmp_path_factory.mktemp("hostile")) as robot:
        yield robot


def test_the_executive_survives_malformed_messages_and_requests(robot: RobotProcess) -> None:
    login = security.find_login(robot.robot.name, security.SERVICE, [robot.folder])
    assert login is not None
    prefix = f"dura/{robot.robot.name}/"
    config = session_config(connect=(robot.endpoint,), login=login)
    answers: list[str] = []
    with (
        Bus(robot.robot.name, name="hostile", endpoint=robot.endpoint, login=login) as bus,
        zenoh.open(config) as session,
    ):
        for key in [k for k in KEYS if k not in UNHEARD]:  # what is sent reaches someone
            assert bus.wait_for_subscriber(key), f"nobody listens to {key}"
        for key in KEYS:
            for payload in GARBAGE:
                bus.publish_raw(key, payload)
        for verb in VERBS:
            for payload in GARBAGE[:7]:
                key = f"{verb.key}/hostile" if verb.caller else verb.key
                for reply in session.get(prefix + key, payload=payload, timeout=10.0):
                    answers.append("ok" if reply.ok is not None else "error")
        # the executive handles what it got in threads of its own, and nothing tells
        # when they are through: give a failure the time to show
        time.sleep(1.0)
    assert robot.running
    status = robot.status()  # the high level still reads (and serves) its state
    assert status.robot == "usecase"
    assert isinstance(status.diagnoses, DiagnosisInfo | planning.NoDiagnosis)
    assert len(answers) == len(VERBS) * 7  # every request answered, none left hanging
    assert answers.count("error") >= len(VERBS) * 5  # what is not an object is refused
    log = robot.log_tail(100_000)
    assert "Traceback" not in log, log[-3000:]


def test_dura_status_reads_after_the_attack(robot: RobotProcess) -> None:
    done = run_dura(
        "status", "--json", "--robot", str(USECASE), "--endpoint", robot.endpoint, cwd=robot.folder
    )
    assert done.returncode == 0, done.stderr
    assert json.loads(done.stdout)["robot"] == "usecase"


def test_a_forged_diagnosis_never_reaches_the_state(tmp_path: Path) -> None:
    # an operator (the CLI's role) may not publish diagnoses at all
    with RobotProcess(USECASE, tmp_path) as robot:
        operator = robot.login()
        assert operator is not None
        with Bus("usecase", name="operator", endpoint=robot.endpoint, login=operator) as bus:
            assert bus.wait_for_subscriber(DIAGNOSES)  # what it publishes leaves it
            forged = {"status": "DIAGNOSED", "diagnoses": [["lidar"]], "stamp": time.time()}
            for _ in range(3):
                bus.publish(DIAGNOSES, forged)
            # nothing tells that a message was refused: give the forged ones the time
            # they would take to reach the state
            time.sleep(1.0)
        diagnosis = robot.status().diagnosis
        assert diagnosis is None or not diagnosis.diagnoses
        assert robot.status().faults == []
