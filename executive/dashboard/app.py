"""The dashboard's web application (Starlette): the page, its assets, the live stream,
the pictures, and the two changes a page may make (add and cancel goals).

Routes:

- ``GET /``: the page; ``/static/...``: its script and style sheet (served from this
  package: a robot often has no internet).
- ``GET /api/stream``: server-sent events, every view first (``status``, ``goals``,
  ``plan``, ``components``, ``observations``, ``events``), then views that changed and
  new ``event`` and ``observation`` items as they come.
- ``GET /api/plan.svg``, ``GET /api/graph.svg``: the pictures as files.
- ``POST /api/goals`` ``{"expression", "priority", "deadline"}``: add a goal through the
  executive's ``goal/add`` verb; ``POST /api/goals/{id}/cancel``: cancel one. A refused
  request answers 400 with ``{"error": reason}``, the executive's own words.
"""

from __future__ import annotations

import asyncio
import contextlib
import json
import time
from collections.abc import AsyncIterator, Awaitable, Callable, MutableMapping
from http.cookies import SimpleCookie
from pathlib import Path
from typing import Any
from urllib.parse import parse_qs

from starlette.applications import Starlette
from starlette.requests import Request
from starlette.responses import FileResponse, JSONResponse, Response, StreamingResponse
from starlette.routing import Mount, Route
from starlette.staticfiles import StaticFiles

from executive.bus.api import planning
from executive.bus.schema import plain
from executive.dashboard import gantt, graph
from executive.dashboard.access import COOKIE, Access
from executive.dashboard.feed import Feed
from executive.dashboard.live import GOALS, PLAN
from knowledge.errors import DuraError
from knowledge.records import Goal

STATIC = Path(__file__).resolve().parent / "static"
MAX_BODY = 16 * 1024  # bytes of a request body: a goal is a line of text
BODY_TIMEOUT = 10.0  # seconds a client has to send a request's body

Scope = MutableMapping[str, Any]
Receive = Callable[[], Awaitable[MutableMapping[str, Any]]]
Send = Callable[[MutableMapping[str, Any]], Awaitable[None]]
ASGIApp = Callable[[Scope, Receive, Send], Awaitable[None]]

SECURITY_HEADERS = [
    (b"x-content-type-options", b"nosniff"),
    (b"x-frame-options", b"DENY"),
    (b"referrer-policy", b"no-referrer"),
    (
        b"content-security-policy",
        b"default-src 'self'; img-src 'self' data:; style-src 'self' 'unsafe-inline'; "
        b"frame-ancestors 'none'",
    ),
]


class Guard:
    """ASGI middleware: the access rule (:class:`Access`) before anything else."""

    def __init__(self, app: ASGIApp, access: Access, realm: str) -> None:
        self.app = app
        self.access = access
        self.realm = realm

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        if scope["type"] != "http":
            await self.app(scope, receive, send)
            return
        headers = {k.decode("latin-1").lower(): v.decode("latin-1") for k, v in scope["headers"]}
        client = scope.get("client")
        query = parse_qs(scope.get("query_string", b"").decode("latin-1"))
        token = (query.get("token") or [None])[0]
        cookies = {k: m.value for k, m in SimpleCookie(headers.get("cookie", "")).items()}
        if not self.access.host_allowed(headers.get("host", "")):
            await _plain(send, 421, "this dashboard answers only to its own address")
            return
        if not self.access.allows(client[0] if client else None, headers, cookies, token):
            challenge = f'Basic realm="{self.realm}", charset="UTF-8"'.encode()
            await _plain(send, 401, "the robot's operator credentials are needed",
                         [(b"www-authenticate", challenge)])  # fmt: skip
            return
        if scope["method"] == "POST" and not Access.same_origin(headers):
            await _plain(send, 403, "changes come only from the dashboard's own page")
            return
        if scope["method"] != "GET":  # the whole body first, in time and in size
            body = await _body(receive)
            if isinstance(body, tuple):
                await _plain(send, *body)
                return
            receive = _replay(body, receive)
        set_cookie = token is not None and token == self.access.token

        async def send_with_headers(message: MutableMapping[str, Any]) -> None:
            if message["type"] == "http.response.start":
                extra = list(SECURITY_HEADERS)
                if set_cookie:
                    extra.append((b"set-cookie",
                                  f"{COOKIE}={token}; HttpOnly; SameSite=Strict; Path=/".encode()))  # fmt: skip
                message["headers"] = [*message.get("headers", []), *extra]
            await send(message)

        await self.app(scope, receive, send_with_headers)


async def _body(receive: Receive) -> bytes | tuple[int, str]:
    """A request's whole body, or the status and reason that refuse it: more than
    :data:`MAX_BODY` bytes, or not all there within :data:`BODY_TIMEOUT` seconds."""
    parts: list[bytes] = []
    size = 0
    deadline = asyncio.get_running_loop().time() + BODY_TIMEOUT
    while True:
        left = deadline - asyncio.get_running_loop().time()
        try:
            message = await asyncio.wait_for(receive(), max(left, 0.0))
        except TimeoutError:
            return 408, f"the request's body did not arrive within {BODY_TIMEOUT:g} s"
        if message["type"] != "http.request":
            return 400, "the client went away"
        part = message.get("body", b"")
        size += len(part)
        if size > MAX_BODY:
            return 413, f"a request of at most {MAX_BODY} bytes"
        parts.append(part)
        if not message.get("more_body", False):
            return b"".join(parts)


def _replay(body: bytes, receive: Receive) -> Receive:
    """A ``receive`` that gives the body read already, then what the client sends."""
    given = False

    async def replay() -> MutableMapping[str, Any]:
        nonlocal given
        if given:
            return await receive()
        given = True
        return {"type": "http.request", "body": body, "more_body": False}

    return replay


async def _plain(
    send: Send, status: int, text: str, headers: list[tuple[bytes, bytes]] | None = None
) -> None:
    body = (text + "\n").encode()
    await send(
        {
            "type": "http.response.start",
            "status": status,
            "headers": [(b"content-type", b"text/plain; charset=utf-8"),
                        (b"content-length", str(len(body)).encode()), *(headers or [])],
        }
    )  # fmt: skip
    await send({"type": "http.response.body", "body": body})


def create_app(feed: Feed, access: Access) -> ASGIApp:
    """The dashboard of the robot ``feed`` follows, guarded by ``access``."""
    state = feed.state

    async def index(request: Request) -> Response:
        return FileResponse(STATIC / "index.html", headers={"cache-control": "no-cache"})

    async def stream(request: Request) -> Response:
        return StreamingResponse(
            feed.stream(),
            media_type="text/event-stream",
            headers={"cache-control": "no-cache", "x-accel-buffering": "no"},
        )

    async def plan_svg(request: Request) -> Response:
        if state.plan is None:
            return JSONResponse({"error": "no plan yet"}, status_code=404)
        chart = gantt.live_gantt(state.plan, state.execution, state.plan_events, state.tasks,
                                 time.time(), robots=state.robots)  # fmt: skip
        return Response(gantt.render(chart), media_type="image/svg+xml")

    async def graph_svg(request: Request) -> Response:
        picture = graph.render(state.layout, state.graph_state())
        return Response(picture, media_type="image/svg+xml")

    async def add_goal(request: Request) -> Response:
        body = await _json(request)
        if isinstance(body, Response):
            return body
        try:
            goal = planning.GoalAdd.from_payload({**body, "source": "user"})
        except DuraError as e:
            return JSONResponse({"error": str(e)}, status_code=400)
        return await _call(lambda: planning.GOAL_ADD.call(feed.bus, goal).goal)

    async def cancel_goal(request: Request) -> Response:
        try:
            goal_id = planning.GoalId.from_payload({"id": int(request.path_params["goal"])})
        except (ValueError, DuraError) as e:
            return JSONResponse({"error": f"not a goal id: {e}"}, status_code=400)
        return await _call(lambda: planning.GOAL_CANCEL.call(feed.bus, goal_id).goal)

    async def _call(ask: Callable[[], Goal]) -> Response:
        try:
            goal = await asyncio.to_thread(ask)
        except DuraError as e:
            return JSONResponse({"error": str(e)}, status_code=400)
        feed.ask(GOALS, PLAN)
        return JSONResponse({"goal": plain(goal)})

    @contextlib.asynccontextmanager
    async def lifespan(app: Starlette) -> AsyncIterator[None]:
        await feed.start()
        try:
            yield
        finally:
            await feed.stop()

    app = Starlette(
        routes=[
            Route("/", index),
            Route("/api/stream", stream),
            Route("/api/plan.svg", plan_svg),
            Route("/api/graph.svg", graph_svg),
            Route("/api/goals", add_goal, methods=["POST"]),
            Route("/api/goals/{goal}/cancel", cancel_goal, methods=["POST"]),
            Mount("/static", StaticFiles(directory=STATIC), name="static"),
        ],
        lifespan=lifespan,
    )
    return Guard(app, access, f"dura {state.robot.name}")


async def _json(request: Request) -> dict[str, Any] | Response:
    """A request's JSON object, or the response that refuses it."""
    if request.headers.get("content-type", "").split(";")[0].strip() != "application/json":
        return JSONResponse({"error": "send JSON (application/json)"}, status_code=415)
    declared = request.headers.get("content-length", "0")
    too_long = declared.isdigit() and int(declared) > MAX_BODY
    raw = b"" if too_long else await request.body()
    if too_long or len(raw) > MAX_BODY:
        return JSONResponse({"error": f"a request of at most {MAX_BODY} bytes"}, status_code=413)
    try:
        body = json.loads(raw)
    except (UnicodeDecodeError, json.JSONDecodeError) as e:
        return JSONResponse({"error": f"not JSON: {e}"}, status_code=400)
    if not isinstance(body, dict):
        return JSONResponse({"error": "send a JSON object"}, status_code=400)
    return body
