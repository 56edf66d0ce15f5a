"""A dashboard of a robot with credentials, asked by real HTTP clients: without the
operator's credentials nothing is shown or changed, from this machine too; a page that
renames itself (DNS rebinding) is refused; a slow client holds no connection."""

from __future__ import annotations

import http.client
import json
import socket
from collections.abc import Iterator
from pathlib import Path
from urllib.parse import urlsplit

import pytest

from executive.dashboard import app, server
from executive.dashboard.server import Dashboard
from executive.testing.harness import RobotProcess
from tests.conftest import USECASE

GOAL = json.dumps({"expression": "(picture_taken lab)"})


@pytest.fixture(scope="module")
def robot(tmp_path_factory: pytest.TempPathFactory) -> Iterator[RobotProcess]:
    with RobotProcess(USECASE, tmp_path_factory.mktemp("guarded-dashboard")) as robot:
        yield robot


@pytest.fixture(scope="module")
def page(robot: RobotProcess) -> Iterator[Dashboard]:
    with Dashboard.connect(robot.robot, robot.endpoint, port=0, folders=[robot.folder]) as page:
        yield page


def ask(
    port: int,
    method: str,
    path: str,
    *,
    host: str = "127.0.0.1",
    body: str | None = None,
    headers: dict[str, str] | None = None,
) -> http.client.HTTPResponse:
    connection = http.client.HTTPConnection("127.0.0.1", port, timeout=10)
    sent = {"Host": host, "Content-Type": "application/json", **(headers or {})}
    connection.request(method, path, body=body, headers=sent)
    response = connection.getresponse()
    response.read()
    connection.close()
    return response


def test_without_credentials_a_local_user_sees_and_changes_nothing(
    robot: RobotProcess, page: Dashboard
) -> None:
    refused = [
        ask(page.port, "GET", "/").status,
        ask(page.port, "GET", "/api/stream").status,
        ask(page.port, "POST", "/api/goals", body=GOAL).status,
        ask(page.port, "POST", "/api/goals/1/cancel").status,
        ask(page.port, "GET", "/?token=guess").status,
    ]
    assert refused == [401] * len(refused)
    assert robot.goals() == []


def test_the_printed_link_opens_the_page_and_its_cookie_keeps_it_open(
    robot: RobotProcess, page: Dashboard
) -> None:
    link = urlsplit(page.url)
    assert link.query.startswith("token=")
    opened = ask(page.port, "GET", f"/?{link.query}")
    assert opened.status == 200
    cookie = opened.getheader("set-cookie", "").split(";")[0]
    added = ask(page.port, "POST", "/api/goals", body=GOAL, headers={"Cookie": cookie})
    assert added.status == 200
    assert len(robot.goals()) == 1


def test_a_page_that_renames_itself_is_refused(tmp_path: Path, robot: RobotProcess) -> None:
    anywhere = "0.0.0.0"  # noqa: S104 - every interface, as a robot's dashboard may listen
    with Dashboard.connect(
        robot.robot, robot.endpoint, host=anywhere, port=0, folders=[robot.folder]
    ) as wide:
        token = {"Cookie": f"dura_dashboard={wide.access.token}"}
        rebound = ask(wide.port, "POST", "/api/goals", host="attacker.example", body=GOAL,
                      headers={**token, "Origin": "http://attacker.example"})  # fmt: skip
        assert rebound.status == 421
        assert ask(wide.port, "GET", "/", host="attacker.example:80", headers=token).status == 421
        assert ask(wide.port, "GET", "/", host="127.0.0.1", headers=token).status == 200
        assert ask(wide.port, "GET", "/", host=socket.gethostname(), headers=token).status == 200
    with Dashboard.connect(robot.robot, robot.endpoint, port=0, folders=[robot.folder]) as local:
        token = {"Cookie": f"dura_dashboard={local.access.token}"}
        assert ask(local.port, "GET", "/", host="attacker.example", headers=token).status == 421


def test_a_slow_client_holds_no_connection(
    page: Dashboard, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setattr(server, "HEADER_TIMEOUT", 0.5)
    monkeypatch.setattr(app, "BODY_TIMEOUT", 0.5)
    with socket.create_connection(("127.0.0.1", page.port), timeout=10) as slow:
        slow.sendall(b"GET / HTTP/1.1\r\nHost: 127.0.0.1\r\n")  # never ends its headers
        assert slow.recv(1024) == b""  # the server ended the connection, answering nothing
    with socket.create_connection(("127.0.0.1", page.port), timeout=10) as slow:
        cookie = f"dura_dashboard={page.access.token}"
        slow.sendall(
            f"POST /api/goals HTTP/1.1\r\nHost: 127.0.0.1\r\nCookie: {cookie}\r\n"
            "Content-Type: application/json\r\nContent-Length: 100\r\n\r\n{".encode()
        )  # promises 100 bytes, sends one
        answer = slow.recv(1024)
    assert answer.startswith(b"HTTP/1.1 408"), answer
