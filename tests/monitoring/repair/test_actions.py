"""Repair actions against real things: files, processes, an SMTP server, the bus."""

from __future__ import annotations

import os
import socket
import sys
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
from aiosmtpd.controller import Controller

from executive.bus.api import planning, tasks
from executive.bus.keys import api
from executive.bus.payloads import ComponentState
from executive.bus.session import Bus
from executive.bus.states import Lifecycle
from knowledge.errors import BusError, DuraError
from knowledge.records import Goal, GoalState
from monitoring.repair.action import ActionContext, Firing
from monitoring.repair.rule import Rule, read_rules

FIRING = Firing("lidar_down", ("lidar", "lidar_filter"), ("frequency[scan]",), time.time())


def action(tmp_path: Path, entry: str) -> Rule:
    path = tmp_path / "rules.yaml"
    path.write_text("rules:\n  - " + entry + "\n")
    return read_rules(path).rules[0]


def test_the_log_action_appends_a_line_to_its_file(tmp_path: Path) -> None:
    rule = action(
        tmp_path,
        "{type: log, file: logs/repair.log, message: '$rule: $faulty', "
        "positive_observations: [{type: hz, resource: scan}]}",
    )
    rule.action.run(ActionContext(folder=tmp_path), FIRING)
    rule.action.run(ActionContext(folder=tmp_path), FIRING)
    lines = (tmp_path / "logs" / "repair.log").read_text().splitlines()
    assert len(lines) == 2 and lines[0].endswith(" lidar_down: lidar, lidar_filter")


def test_the_process_action_runs_its_argv_without_a_shell(tmp_path: Path) -> None:
    rule = action(
        tmp_path,
        f'{{type: process, process: [{sys.executable}, -c, \'open("out.txt", "w").write("$rule;")\'], '
        "positive_observations: [{type: hz, resource: scan}]}",
    )
    rule.action.run(ActionContext(folder=tmp_path), FIRING)
    assert (tmp_path / "out.txt").read_text() == "lidar_down;"


def test_a_process_that_fails_or_hangs_is_a_failure_and_is_killed(tmp_path: Path) -> None:
    failing = action(
        tmp_path,
        f"{{type: process, process: [{sys.executable}, -c, 'raise SystemExit(3)'], "
        "positive_observations: [{type: hz, resource: scan}]}",
    )
    with pytest.raises(DuraError, match="exited with 3"):
        failing.action.run(ActionContext(folder=tmp_path), FIRING)
    hanging = action(
        tmp_path,
        f"{{type: process, timeout: 0.5, process: [{sys.executable}, -c, "
        '\'import os,time; open("pid","w").write(str(os.getpid())); time.sleep(60)\'], '
        "positive_observations: [{type: hz, resource: scan}]}",
    )
    with pytest.raises(DuraError, match=r"did not end within 0.5 s \(killed\)"):
        hanging.action.run(ActionContext(folder=tmp_path), FIRING)
    pid = int((tmp_path / "pid").read_text())
    with pytest.raises(ProcessLookupError):
        os.kill(pid, 0)


class Inbox:
    def __init__(self) -> None:
        self.messages: list[Any] = []

    async def handle_DATA(self, server: Any, session: Any, envelope: Any) -> str:
        self.messages.append(envelope)
        return "250 OK"


@pytest.fixture
def smtp() -> Iterator[tuple[int, Inbox]]:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    inbox = Inbox()
    controller = Controller(inbox, hostname="127.0.0.1", port=port)
    controller.start()
    try:
        yield port, inbox
    finally:
        controller.stop()


def test_the_mail_action_sends_a_real_mail(tmp_path: Path, smtp: tuple[int, Inbox]) -> None:
    port, inbox = smtp
    rule = action(
        tmp_path,
        f"{{type: email, host: 127.0.0.1, port: {port}, from_address: robot@localhost, "
        "to_address: [ops@localhost], subject: 'dura: $rule', content: 'faulty: $faulty', "
        "positive_observations: [{type: hz, resource: scan}]}",
    )
    rule.action.run(ActionContext(folder=tmp_path), FIRING)
    assert len(inbox.messages) == 1
    envelope = inbox.messages[0]
    assert envelope.mail_from == "robot@localhost" and envelope.rcpt_tos == ["ops@localhost"]
    text = envelope.content.decode()
    assert "Subject: dura: lidar_down" in text and "faulty: lidar, lidar_filter" in text


def test_the_mail_action_fails_when_no_server_answers(tmp_path: Path) -> None:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    rule = action(
        tmp_path,
        f"{{type: mail, port: {port}, host: 127.0.0.1, from_address: a@b, to_address: c@d, "
        "timeout: 2, positive_observations: [{type: hz, resource: scan}]}",
    )
    with pytest.raises(OSError):
        rule.action.run(ActionContext(folder=tmp_path), FIRING)


@pytest.fixture
def executive(endpoint: str) -> Iterator[tuple[Bus, list[tuple[str, dict[str, Any]]]]]:
    """A stand-in for the executive: serves the API keys the actions call and records them.

    Declared verbs answer with their declared replies (a refusal is an error reply, as
    the executive's); the verbs a rule names freely answer ``ok``.
    """
    requests: list[tuple[str, dict[str, Any]]] = []
    with Bus("testbot", name="executive", endpoint=endpoint, listen=True) as server:
        for verb in (tasks.COMPONENT_RESTART, tasks.COMPONENT_FAULT):

            def fault(request: tasks.ComponentFault, key: str = verb.key) -> tasks.FaultReply:
                requests.append((key.removeprefix("executive/api/"), request.to_payload()))
                if request.name == "unknown":
                    raise DuraError("no component 'unknown'")
                return tasks.FaultReply(ComponentState(request.name, Lifecycle.READY), 1, False)

            verb.serve(server, fault)

        def goal(request: planning.GoalAdd) -> planning.GoalReply:
            requests.append(("goal/add", request.to_payload()))
            return planning.GoalReply(Goal(1, request.expression, GoalState.PENDING))

        planning.GOAL_ADD.serve(server, goal)
        for verb_name in ("parameter/set", "replan"):

            def handle(payload: dict[str, Any], verb_name: str = verb_name) -> dict[str, Any]:
                requests.append((verb_name, payload))
                return {"ok": True}

            server.serve(api(verb_name), handle)
        with Bus("testbot", name="rules", endpoint=endpoint) as client:
            yield client, requests


@pytest.mark.parametrize(
    ("entry", "verb", "payload"),
    [
        (
            "{type: restart, component: lidar}",
            "component/restart",
            {"name": "lidar", "reason": "rule lidar_down fired"},
        ),
        (
            "{type: fault, component: lidar, reason: '$failed'}",
            "component/fault",
            {"name": "lidar", "reason": "frequency[scan]"},
        ),
        (
            "{type: goal, expression: '(at robot base)', goal_priority: 5}",
            "goal/add",
            {"expression": "(at robot base)", "priority": 5, "source": "rule", "keep": False},
        ),
        (
            "{type: parameter, component: lidar, key: rate, value: 5.0}",
            "parameter/set",
            {"component": "lidar", "key": "rate", "value": 5.0},
        ),
        ("{type: command, verb: replan, payload: {why: $rule}}", "replan", {"why": "lidar_down"}),
    ],
    ids=["restart", "fault", "goal", "parameter", "command"],
)
def test_executive_actions_send_their_request_on_the_bus(
    tmp_path: Path,
    executive: tuple[Bus, list[tuple[str, dict[str, Any]]]],
    entry: str,
    verb: str,
    payload: dict[str, Any],
) -> None:
    bus, requests = executive
    rule = action(tmp_path, entry[:-1] + ", positive_observations: [{type: hz, resource: scan}]}")
    rule.action.run(ActionContext(bus, tmp_path), FIRING)
    assert requests == [(verb, payload)]


def test_a_refused_executive_request_is_a_failure_naming_the_reason(
    tmp_path: Path, executive: tuple[Bus, list[tuple[str, dict[str, Any]]]]
) -> None:
    bus, _ = executive
    rule = action(
        tmp_path,
        "{type: restart, component: unknown, positive_observations: [{type: hz, resource: scan}]}",
    )
    with pytest.raises(BusError, match="no component 'unknown'"):
        rule.action.run(ActionContext(bus, tmp_path), FIRING)
