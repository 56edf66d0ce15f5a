"""Run the dashboard: uvicorn serving :mod:`executive.dashboard.app` on a thread of its
own, beside whatever else the process does (``dura dashboard``, ``dura run
--dashboard``, ``dura demo --dashboard``)."""

from __future__ import annotations

import contextlib
import socket
import threading
import time
from pathlib import Path
from typing import Any

import uvicorn
from uvicorn.protocols.http.h11_impl import H11Protocol

from executive.bus.security import OPERATOR, find_login
from executive.bus.session import Bus
from executive.dashboard.access import DEFAULT_HOST, DEFAULT_PORT, Access, is_loopback
from executive.dashboard.app import create_app
from executive.dashboard.feed import Feed
from executive.dashboard.live import LiveState
from knowledge.description import RobotDescription
from knowledge.errors import DuraError

START_TIMEOUT = 15.0  # seconds for the server to listen
HEADER_TIMEOUT = 10.0  # seconds a client has to send a request's headers


class DashboardError(DuraError):
    """The dashboard cannot be served (port in use, no credentials for a remote one)."""


class Dashboard:
    """The dashboard of one robot, served on ``host:port`` (port 0: a free one).

    Args:
        robot: the robot's description (its graph).
        bus: a session with the robot's executive; the caller keeps and closes it.
        password: the operator's bus password; required to listen beyond loopback.
        allow: host names a request may call it by, beyond loopback names and IP
            addresses (and this machine's names, when it listens beyond loopback).
        fleet: ``robot`` is a fleet's (``dura fleet run``): its goals, plan by robot and
            events are shown; components and observations are its robots' own.

    Raises:
        DashboardError: listening beyond loopback without credentials.
    """

    def __init__(
        self,
        robot: RobotDescription,
        bus: Bus,
        *,
        host: str = DEFAULT_HOST,
        port: int = DEFAULT_PORT,
        password: str | None = None,
        allow: tuple[str, ...] = (),
        fleet: bool = False,
    ) -> None:
        if not is_loopback(host) and password is None:
            raise DashboardError(
                f"the dashboard listens on {host} (beyond loopback) only with the robot's bus "
                f"credentials, and robot '{robot.name}' has none here (.dura/{robot.name}"
                ".bus.json): listen on 127.0.0.1, or run it where the executive runs"
            )
        self.robot = robot
        self.host = host
        names = allow if is_loopback(host) else (*allow, *_own_names())
        self.access = Access(host, password, names)
        self.feed = Feed(bus, LiveState(robot, fleet=fleet))
        self._socket = _listen(host, port)
        self.port = int(self._socket.getsockname()[1])
        config = uvicorn.Config(
            create_app(self.feed, self.access),
            log_level="warning",
            access_log=False,
            lifespan="on",
            http=SlowClientsEnd,
            ws="none",
            timeout_graceful_shutdown=2,
        )
        self._server = uvicorn.Server(config)
        self._thread: threading.Thread | None = None
        self._own_bus: Bus | None = None

    @classmethod
    def connect(
        cls,
        robot: RobotDescription,
        endpoint: str,
        *,
        host: str = DEFAULT_HOST,
        port: int = DEFAULT_PORT,
        folders: list[Path] | None = None,
        allow: tuple[str, ...] = (),
        fleet: bool = False,
    ) -> Dashboard:
        """A dashboard with a bus session of its own, as the robot's operator (the
        credentials in ``.dura/`` of ``folders``, default the working folder and the
        description's), closed when the dashboard stops.

        Raises:
            BusError: no executive answers at ``endpoint``, or the credentials are unusable.
            DashboardError: see the class.
        """
        folders = folders if folders is not None else [Path.cwd(), robot.path.parent]
        login = find_login(robot.name, OPERATOR, folders)
        bus = Bus(robot.name, name="dashboard", endpoint=endpoint, login=login)
        try:
            dashboard = cls(robot, bus, host=host, port=port, allow=allow, fleet=fleet,
                            password=None if login is None else login.password)  # fmt: skip
        except BaseException:
            bus.close()
            raise
        dashboard._own_bus = bus
        return dashboard

    @property
    def url(self) -> str:
        """The page's address, with the token when the robot has credentials (the one
        link that opens the page: keep it to yourself)."""
        host = self.host
        if host in ("0.0.0.0", "::", ""):  # noqa: S104 - naming it, not binding it
            host = socket.gethostname()
        shown = f"[{host}]" if ":" in host else host
        token = "" if self.access.token is None else f"?token={self.access.token}"
        return f"http://{shown}:{self.port}/{token}"

    def start(self, timeout: float = START_TIMEOUT) -> Dashboard:
        """Serve on a thread of its own; returns once it listens.

        Raises:
            DashboardError: the server did not start (the reason is logged).
        """
        self._thread = threading.Thread(
            target=self._server.run, kwargs={"sockets": [self._socket]},
            name="dashboard", daemon=True,
        )  # fmt: skip
        self._thread.start()
        deadline = time.monotonic() + timeout
        while not self._server.started:
            if not self._thread.is_alive() or time.monotonic() > deadline:
                self.stop()
                raise DashboardError(f"the dashboard did not start on {self.url}")
            time.sleep(0.02)
        return self

    def stop(self) -> None:
        """Stop serving (every page's stream ends) and wait for the thread."""
        self.feed.close_streams()
        self._server.should_exit = True
        if self._thread is not None:
            self._thread.join(10.0)
            self._thread = None
        with contextlib.suppress(OSError):
            self._socket.close()
        if self._own_bus is not None:
            self._own_bus.close()
            self._own_bus = None

    def __enter__(self) -> Dashboard:
        return self.start()

    def __exit__(self, *exc: Any) -> None:
        self.stop()


def _listen(host: str, port: int) -> socket.socket:
    family = socket.AF_INET6 if ":" in host else socket.AF_INET
    sock = socket.socket(family, socket.SOCK_STREAM)
    sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
    try:
        sock.bind((host, port))
    except OSError as e:
        sock.close()
        raise DashboardError(f"the dashboard cannot listen on {host}:{port}: {e.strerror}") from e
    sock.listen(64)
    sock.set_inheritable(False)
    return sock


def _own_names() -> tuple[str, ...]:
    """This machine's names, as a visitor elsewhere may call it."""
    names = {socket.gethostname()}
    with contextlib.suppress(OSError):
        names.add(socket.getfqdn())
    return tuple(sorted(n for n in names if n))


class SlowClientsEnd(H11Protocol):
    """uvicorn's HTTP/1.1 protocol, ending a connection whose request headers are not
    complete within :data:`HEADER_TIMEOUT` seconds (a slow client holds no connection;
    uvicorn itself waits for ever). Bodies have their own limit (:mod:`.app`)."""

    def connection_made(self, transport: Any) -> None:
        super().connection_made(transport)
        self._arm()

    def on_response_complete(self) -> None:
        super().on_response_complete()
        self._arm()

    def _arm(self) -> None:
        served = self.cycle
        self.loop.call_later(HEADER_TIMEOUT, self._headers_late, served)

    def _headers_late(self, served: Any) -> None:
        # no new request began since the timer started: the headers have not arrived
        if self.cycle is served and not self.transport.is_closing():
            self.transport.close()
