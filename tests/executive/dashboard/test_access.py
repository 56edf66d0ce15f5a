"""Who may open the dashboard: the robot's operator credentials, from this machine too."""

from __future__ import annotations

import asyncio
import base64
from collections.abc import MutableMapping
from typing import Any

import pytest

from executive.dashboard.access import Access, host_name, is_loopback
from executive.dashboard.app import Guard

SECRET = "s3cret-password"  # noqa: S105 - a test's password
ANYWHERE = "0.0.0.0"  # noqa: S104 - what a dashboard listening beyond loopback is given


def basic(user: str, password: str) -> dict[str, str]:
    return {"authorization": "Basic " + base64.b64encode(f"{user}:{password}".encode()).decode()}


@pytest.mark.parametrize(
    ("host", "loopback"),
    [("127.0.0.1", True), ("127.8.9.10", True), ("::1", True), ("[::1]", True),
     ("localhost", True), (ANYWHERE, False), ("192.168.1.5", False), ("robot.local", False)],
)  # fmt: skip
def test_loopback_is_this_machine_only(host: str, loopback: bool) -> None:
    assert is_loopback(host) is loopback


def test_the_host_of_a_host_header_drops_the_port() -> None:
    assert host_name("127.0.0.1:8470") == "127.0.0.1"
    assert host_name("[::1]:8470") == "::1"
    assert host_name("localhost") == "localhost"


def test_a_loopback_client_needs_the_credentials_when_the_robot_has_them() -> None:
    assert Access("127.0.0.1").allows("127.0.0.1", {}, {})  # a robot without credentials
    assert not Access("127.0.0.1", SECRET).allows("127.0.0.1", {}, {})
    assert not Access(ANYWHERE, SECRET).allows("::1", {}, {})
    assert Access("127.0.0.1", SECRET).allows("127.0.0.1", basic("operator", SECRET), {})


def test_another_client_needs_the_operators_password_or_its_token() -> None:
    access = Access(ANYWHERE, SECRET)
    assert not access.allows("192.0.2.7", {}, {})
    assert access.allows("192.0.2.7", basic("operator", SECRET), {})
    assert not access.allows("192.0.2.7", basic("operator", "guess"), {})
    assert not access.allows("192.0.2.7", basic("lidar", SECRET), {})
    token = access.token
    assert token and SECRET not in token
    assert access.allows("192.0.2.7", {}, {}, token)
    assert access.allows("192.0.2.7", {}, {"dura_dashboard": token})
    assert access.allows("192.0.2.7", {"authorization": f"Bearer {token}"}, {})
    assert not access.allows("192.0.2.7", {}, {}, token[:-1] + "x")


def test_without_credentials_nobody_else_gets_in() -> None:
    assert not Access(ANYWHERE).allows("192.0.2.7", basic("operator", ""), {})


def test_every_dashboard_answers_only_to_the_names_of_its_allow_list() -> None:
    assert Access("127.0.0.1").host_allowed("localhost:8470")
    assert not Access("127.0.0.1").host_allowed("attacker.example:8470")
    assert not Access("127.0.0.1").host_allowed("")
    anywhere = Access(ANYWHERE, SECRET, ("robot.local",))
    assert anywhere.host_allowed("robot.local:8470")
    assert anywhere.host_allowed("ROBOT.LOCAL.")
    assert anywhere.host_allowed("192.168.1.5:8470") and anywhere.host_allowed("[fe80::1]:8470")
    assert anywhere.host_allowed("localhost")
    assert not anywhere.host_allowed("attacker.example:8470")  # DNS rebinding
    assert not Access(ANYWHERE, SECRET).host_allowed("robot.local:8470")  # not on its list


def test_a_change_must_come_from_the_same_origin() -> None:
    assert Access.same_origin({"host": "127.0.0.1:8470"})
    assert Access.same_origin({"host": "127.0.0.1:8470", "origin": "http://127.0.0.1:8470"})
    assert not Access.same_origin({"host": "127.0.0.1:8470", "origin": "http://evil.example"})


def ask(access: Access, client: str, headers: dict[str, str], query: str = "") -> dict[str, Any]:
    """What the guard answers a GET / from ``client`` (the app behind it says 200)."""
    sent: list[MutableMapping[str, Any]] = []

    async def app(scope: Any, receive: Any, send: Any) -> None:
        await send({"type": "http.response.start", "status": 200, "headers": []})
        await send({"type": "http.response.body", "body": b"ok"})

    async def receive() -> MutableMapping[str, Any]:
        return {"type": "http.request", "body": b""}

    async def send(message: MutableMapping[str, Any]) -> None:
        sent.append(message)

    scope = {"type": "http", "method": "GET", "path": "/", "client": (client, 50000),
             "query_string": query.encode(),
             "headers": [(k.encode(), v.encode()) for k, v in headers.items()]}  # fmt: skip
    asyncio.run(Guard(app, access, "dura usecase")(scope, receive, send))
    start = sent[0]
    return {
        "status": start["status"],
        "headers": {k.decode(): v.decode() for k, v in start["headers"]},
    }


def test_the_guard_asks_a_remote_visitor_to_log_in_as_the_operator() -> None:
    access = Access(ANYWHERE, SECRET, ("robot.local",))
    host = {"host": "robot.local:8470"}
    refused = ask(access, "192.0.2.7", host)
    assert refused["status"] == 401
    assert refused["headers"]["www-authenticate"].startswith('Basic realm="dura usecase"')
    assert ask(access, "192.0.2.7", {**host, **basic("operator", SECRET)})["status"] == 200
    answered = ask(access, "192.0.2.7", host, f"token={access.token}")
    assert answered["status"] == 200
    assert answered["headers"]["set-cookie"].startswith(f"dura_dashboard={access.token};")
    assert "HttpOnly" in answered["headers"]["set-cookie"]


def test_every_answer_forbids_framing_and_sniffing() -> None:
    answered = ask(Access("127.0.0.1"), "127.0.0.1", {"host": "127.0.0.1:8470"})
    assert answered["headers"]["x-frame-options"] == "DENY"
    assert "default-src 'self'" in answered["headers"]["content-security-policy"]
