"""The message bus: a thin wrapper over one eclipse-zenoh session.

Every key lives under ``dura/<robot>/``. Payloads are JSON objects with a source
timestamp. Who sent a topic's message is in its key, not in a field the sender
writes: a session publishes ``topic/<name>`` on ``from/<its name>/topic/<name>``, and
Zenoh's access control lets each component's login publish only under its own name
(:mod:`executive.bus.security`); a subscriber of ``topic/<name>`` hears every sender
and gets the name from the key as the message's caller id. Other keys carry the
sender's name in the attachment, which only the executive's own services may publish.
The executive opens the bus listening on its endpoint
(router mode); components and the CLI connect to it as clients. Multicast
scouting is always off: processes meet at explicit endpoints only.
"""

from __future__ import annotations

import contextlib
import json
import re
import threading
import time
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import TYPE_CHECKING, Any

import zenoh

from executive.bus.helpers import Helpers
from executive.bus.keys import heard, listened_key, sender_of, wire_key
from executive.bus.message import MAX_PAYLOAD, Message, decode, encode
from executive.bus.polled import POLL_CAPACITY, Polled, SenderClocks
from executive.bus.security import COMPONENT, Login
from knowledge.errors import QUOTED, BusError, DuraError, NoAnswer, excerpt

if TYPE_CHECKING:
    import logging

_BAD_KEY = re.compile(r"[*$?#\s]|//")
ERROR_REPLY = 2 * QUOTED  # characters of an error reply: a reason and a short quote

Handler = Callable[["Message"], None]
RequestHandler = Callable[[dict[str, Any]], Mapping[str, Any]]


def _log() -> logging.Logger:
    """The bus's logger. ``logging`` loads with the first message: a command-line process
    that never logs never pays for it (see :mod:`executive.cli`)."""
    import logging

    return logging.getLogger("dura.bus")


def check_name(name: str, what: str = "name") -> str:
    """A topic or component name usable in a key expression (no wildcards, no spaces)."""
    name = name.strip("/")
    if not name or _BAD_KEY.search(name):
        raise BusError(f"invalid {what} '{name}' for the bus (no *, $, ?, #, spaces or //)")
    return name


class _Dropped:
    """Counts dropped malformed messages per key; logs the first and then every 100th."""

    def __init__(self) -> None:
        self._counts: dict[str, int] = {}
        self._lock = threading.Lock()

    def __call__(self, key: str, reason: str) -> None:
        with self._lock:
            n = self._counts[key] = self._counts.get(key, 0) + 1
        if n == 1 or n % 100 == 0:
            _log().warning("dropped malformed message #%d on %s: %s", n, key, reason)


def session_config(
    *,
    listen: tuple[str, ...] = (),
    connect: tuple[str, ...] = (),
    login: Login | None = None,
    dictionary: Path | None = None,
    access: Mapping[str, Any] | None = None,
    lease: float | None = None,
) -> zenoh.Config:
    """A zenoh configuration: router if it listens, else client; no multicast scouting.

    ``login`` authenticates this session (a router checks its clients against the
    user-password ``dictionary`` file); ``access`` is Zenoh's access control (see
    :mod:`executive.bus.security`).
    """
    config = zenoh.Config()
    config.insert_json5("mode", json.dumps("router" if listen else "client"))
    if listen:
        config.insert_json5("listen/endpoints", json.dumps(list(listen)))
        # no scouting answers to wait for before it opens (by default 500 ms: later start)
        config.insert_json5("scouting/delay", "0")
        # a router's own messages are the control plane (events, replies): none needs
        # Zenoh's implicit shared memory, whose pool (16 MiB) is resident from the first
        # message above 3 KiB. Components' large messages still pass through as shared
        # memory, and a component's own pool is Zenoh's default.
        config.insert_json5("transport/shared_memory/transport_optimization/enabled", "false")
    if connect:
        config.insert_json5("connect/endpoints", json.dumps(list(connect)))
    config.insert_json5("scouting/multicast/enabled", "false")
    config.insert_json5("scouting/gossip/enabled", "false")
    auth: dict[str, str] = {}
    if login is not None:
        auth.update(user=login.user, password=login.password)
    if dictionary is not None:
        auth["dictionary_file"] = str(dictionary)
    if auth:
        config.insert_json5("transport/auth/usrpwd", json.dumps(auth))
    if access is not None:
        config.insert_json5("access_control", json.dumps(access))
    if lease is not None:  # a lost link is noticed within this time (Zenoh's default: 10 s)
        config.insert_json5("transport/link/tx/lease", str(int(lease * 1000)))
    return config


class Bus:
    """A zenoh session namespaced under ``dura/<robot>/``.

    Args:
        robot: the robot's name, the first level of every key.
        name: this process's component name, sent as caller id.
        endpoint: where the executive listens, e.g. ``tcp/127.0.0.1:7447`` (default: a
            robot description's default).
        listen: listen on ``endpoint`` (the executive) instead of connecting to it.
        connect: further endpoints to connect to (other machines).
        login: the user and password this session authenticates with.
        dictionary, access: (the executive) the users it accepts and what each may do.
        lease: seconds of silence after which a link counts as lost (and the tokens
            declared over it vanish), instead of Zenoh's default of 10.
        component: a component's session, which comes and goes with each start (by
            default: when ``login`` is a component's): it subscribes topics on key
            expressions that no other session declares
            (:func:`executive.bus.keys.listened_key`).

    Raises:
        BusError: the endpoint is unusable: in use (listen) or nobody listens (connect).
    """

    def __init__(
        self,
        robot: str,
        *,
        name: str = "",
        endpoint: str | None = None,
        listen: bool = False,
        connect: tuple[str, ...] = (),
        login: Login | None = None,
        dictionary: Path | None = None,
        access: Mapping[str, Any] | None = None,
        lease: float | None = None,
        component: bool | None = None,
    ) -> None:
        if endpoint is None:
            # here: the robot description's module is not on a quick command's path
            from knowledge.description import DEFAULT_ENDPOINT

            endpoint = DEFAULT_ENDPOINT
        self.robot = check_name(robot, "robot name")
        self.name = name
        self._sender = check_name(name, "sender name").replace("/", "_") if name else "anonymous"
        self.endpoint = endpoint
        if component is None:
            component = login is not None and login.user.startswith(COMPONENT)
        self.component = component
        self.prefix = f"dura/{self.robot}/"
        self._attachment = name.encode()
        self._dropped = _Dropped()
        self._clocks = SenderClocks()  # for Polled: each sender's clock, seen from here
        self._publishers: dict[str, zenoh.Publisher] = {}
        self._declared: list[Any] = []
        self._helpers = Helpers("bus-request")  # threaded handlers answer on them
        self._lock = threading.Lock()
        config = session_config(
            listen=(endpoint,) if listen else (),
            connect=connect if listen else (endpoint, *connect),
            login=login,
            dictionary=dictionary,
            access=access,
            lease=lease,
        )
        try:
            self._session = zenoh.open(config)
        except zenoh.ZError as e:
            if listen:
                raise BusError(
                    f"cannot listen on {endpoint}: {_short(e)} (is an executive already running?)"
                ) from e
            hint = " or it refused these credentials" if login is not None else ""
            raise BusError(
                f"no executive for robot '{robot}' at {endpoint}{hint} ({_short(e)})"
            ) from e

    # --- lifecycle --------------------------------------------------------------------

    def close(self) -> None:
        """Undeclare everything and close the session (idempotent)."""
        with self._lock:
            if self._session.is_closed():
                return
            for entity in reversed(self._declared):
                # RuntimeError "Already borrowed": another thread is using it right now
                # (a publisher mid-put); closing the session undeclares it all the same
                with contextlib.suppress(zenoh.ZError, RuntimeError):
                    entity.undeclare()
            self._declared.clear()
            self._publishers.clear()
            self._session.close()  # type: ignore[no-untyped-call]
        self._helpers.close()

    def __enter__(self) -> Bus:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    @property
    def closed(self) -> bool:
        return bool(self._session.is_closed())

    def key(self, relative: str) -> str:
        return self.prefix + relative

    # --- publish / subscribe ----------------------------------------------------------

    def publish(self, key: str, payload: Mapping[str, Any]) -> None:
        """Publish a JSON object on ``dura/<robot>/<key>``; adds ``stamp`` if missing."""
        if "stamp" not in payload:
            payload = {**payload, "stamp": time.time()}
        self.publish_raw(key, encode(payload))

    def publish_raw(self, key: str, data: bytes) -> None:
        """Publish bytes that already are a JSON object (hot paths)."""
        publisher = self._publishers.get(key)
        if publisher is None:
            publisher = self._publisher(key)
        publisher.put(data, attachment=self._attachment, timestamp=self._session.new_timestamp())

    def wait_for_subscriber(self, key: str, *, timeout: float = 5.0) -> bool:
        """Wait until a subscriber of ``dura/<robot>/<key>`` is there for this session to
        publish to; whether one was within ``timeout`` seconds.

        A subscription reaches the other sessions a moment after it is declared, and
        what is published on its key before that arrives nowhere. Once this returns
        ``True`` a message published on ``key`` reaches a subscriber (in this process or
        another: Zenoh's matching status of the key's publisher). It does not tell which
        subscriber, nor wait for the others.
        """
        publisher = self._publisher(key)
        matched = threading.Event()

        def on_status(status: zenoh.MatchingStatus) -> None:
            if status.matching:
                matched.set()

        listener = publisher.declare_matching_listener(on_status)
        try:
            # the listener tells changes from now on; one already there is the status
            status: Any = publisher.matching_status  # a MatchingStatus (the stubs: bool)
            return bool(getattr(status, "matching", status)) or matched.wait(timeout)
        finally:
            with contextlib.suppress(zenoh.ZError):
                listener.undeclare()  # type: ignore[no-untyped-call]

    def _publisher(self, key: str) -> zenoh.Publisher:
        """This session's publisher of ``dura/<robot>/<key>``, declared on first use."""
        with self._lock:
            publisher = self._publishers.get(key)
            if publisher is None:
                publisher = self._session.declare_publisher(self.key(wire_key(key, self._sender)))
                self._publishers[key] = publisher
                self._declared.append(publisher)
        return publisher

    def subscribe(self, key: str, handler: Handler, *, decoded: bool = True) -> Any:
        """Call ``handler`` for every message on ``dura/<robot>/<key>`` (wildcards allowed).

        A message of topic data (``topic/...``) has its sender's name, as the key it
        came on tells, as caller id; any other message the name in its attachment.

        With ``decoded`` (the default) malformed payloads are logged and dropped before
        the handler sees them; without it the handler gets the raw message and decodes
        lazily. Exceptions in the handler are logged, never raised into zenoh.
        """
        dropped = self._dropped

        listened, wanted = self._listened(key)

        def on_sample(sample: zenoh.Sample) -> None:
            message = self._message(sample, wanted)
            if message is None:
                return
            try:
                if decoded:
                    message.payload  # noqa: B018 - decode now, drop if malformed
                handler(message)
            except BusError as e:
                dropped(message.key, str(e))
            except Exception:
                _log().exception("handler for %s failed", message.key)

        subscriber = self._session.declare_subscriber(listened, on_sample)
        with self._lock:
            self._declared.append(subscriber)
        return subscriber

    def poll(self, key: str, *, capacity: int = POLL_CAPACITY) -> Polled:
        """Queue the messages on ``dura/<robot>/<key>`` for the caller to take with
        :meth:`Polled.drain` on its own thread (wildcards allowed).

        A handler of :meth:`subscribe` runs on a Python thread of its own, which a busy
        process may leave waiting for the CPU or the interpreter: then what has arrived
        is not handled yet. Zenoh fills this queue without Python, so a drain takes all
        that has arrived. A message's ``received`` time is when it arrived: when Python
        first saw it (as a handler of :meth:`subscribe` stamps it), or for one taken
        before that, its ``sent`` time moved onto this process's clock by the least lag
        stamped from its sender (so a sender's clock offset does not count), at most the
        drain's time (see :mod:`executive.bus.polled`); once ``capacity`` messages wait,
        the oldest is dropped. Malformed payloads are not looked for (the caller decodes
        lazily)."""
        channel: Any = zenoh.handlers.RingChannel(capacity)
        listened, wanted = self._listened(key)
        queue = self._session.declare_subscriber(listened, channel)
        with self._lock:
            self._declared.append(queue)

        def stamper(stamp: Handler) -> Any:
            return self.subscribe(key, stamp, decoded=False)

        def message(sample: zenoh.Sample) -> Message | None:
            return self._message(sample, wanted, report=False)  # the stamper reports a drop

        return Polled(queue, message, self._clocks, stamper, capacity)

    def _listened(self, key: str) -> tuple[str, Callable[[str], bool] | None]:
        """The key expression a subscription of ``key`` declares, and which of the keys
        it matches are ``key``'s (``None``: all)."""
        listened = self.key(listened_key(key, component=self.component))
        return listened, None if self.component else heard(key)

    def _message(
        self, sample: zenoh.Sample, wanted: Callable[[str], bool] | None, *, report: bool = True
    ) -> Message | None:
        """The message of a sample received now; ``None`` if it is another key's than
        ``wanted``, or too large (dropped, and ``report``-ed)."""
        relative, sender = sender_of(str(sample.key_expr)[len(self.prefix) :])
        if wanted is not None and not wanted(relative):
            return None
        if len(sample.payload) > MAX_PAYLOAD:
            if report:
                self._dropped(relative, f"{len(sample.payload)} bytes (at most {MAX_PAYLOAD})")
            return None
        attachment = sample.attachment
        if not sender and attachment is not None:
            sender = attachment.to_bytes().decode(errors="replace")
        stamp = sample.timestamp
        sent = round(stamp.get_time().timestamp() * 1e9) if stamp is not None else None
        return Message.at_ns(relative, sample.payload.to_bytes(), sender, sent, time.time_ns())

    # --- request / reply --------------------------------------------------------------

    def serve(
        self, key: str, handler: RequestHandler, *, threaded: bool = False, caller: str = ""
    ) -> Any:
        """Answer requests on ``dura/<robot>/<key>`` with ``handler(payload) -> reply``.

        With ``caller``, a field name, requests come on ``<key>/<caller's name>`` (see
        :meth:`request`), where access control lets each login ask only under its own
        name, and the handler gets that name in the field, whatever the caller wrote.

        A :class:`DuraError` raised by the handler becomes an error reply with its
        message; a malformed request gets an error reply naming the problem. With
        ``threaded`` each request is answered at once on a helper thread (:mod:`.helpers`):
        handlers that wait (for other messages, processes) must not hold zenoh's thread.
        """

        def respond(query: zenoh.Query) -> None:
            key_expr = str(query.key_expr)
            try:
                raw = query.payload.to_bytes() if query.payload is not None else b"{}"
                request = decode(raw, key_expr)
                if caller:
                    request[caller] = key_expr.rpartition("/")[2]
                reply = handler(request)
                query.reply(query.key_expr, encode(reply))
            except DuraError as e:  # the reason, quoting little of a long request
                query.reply_err(excerpt(str(e), ERROR_REPLY).encode())
            except Exception as e:
                _log().exception("request handler for %s failed", key_expr)
                query.reply_err(f"internal error: {type(e).__name__}: {e}".encode())
            finally:
                query.drop()  # type: ignore[no-untyped-call]

        def on_query(query: zenoh.Query) -> None:
            if threaded:
                self._helpers.run(lambda: respond(query))
            else:
                respond(query)

        queryable = self._session.declare_queryable(
            self.key(f"{key}/*" if caller else key), on_query
        )
        with self._lock:
            self._declared.append(queryable)
        return queryable

    def request(
        self,
        key: str,
        payload: Mapping[str, Any] | None = None,
        *,
        timeout: float = 5.0,
        as_caller: bool = False,
    ) -> dict[str, Any]:
        """Send a request and return the first reply; with ``as_caller`` on
        ``<key>/<this session's name>`` (a verb served with a ``caller``).

        Raises:
            NoAnswer: nobody answered in time (or no service serves the key).
            BusError: the answer is an error (its message).
        """
        if as_caller:
            key = f"{key}/{self._sender}"
        replies = self._session.get(
            self.key(key),
            payload=encode(payload or {}),
            attachment=self._attachment,
            timeout=timeout,
        )
        for reply in replies:
            if reply.ok is not None:
                return decode(reply.ok.payload.to_bytes(), key)
            if reply.err is not None:
                raise BusError(reply.err.payload.to_bytes().decode(errors="replace"))
        raise NoAnswer(
            f"no answer on {self.key(key)} within {timeout:g} s (is the executive running?)"
        )

    # --- liveliness -------------------------------------------------------------------

    def declare_alive(self, key: str) -> Any:
        """Declare a liveliness token that vanishes when this process or its link dies."""
        token = self._session.liveliness().declare_token(self.key(key))
        with self._lock:
            self._declared.append(token)
        return token

    def alive(self, key: str, *, timeout: float = 2.0) -> list[str]:
        """The liveliness tokens under ``key`` there are now (relative keys)."""
        prefix_len = len(self.prefix)
        replies = self._session.liveliness().get(self.key(key), timeout=timeout)
        return sorted(str(r.ok.key_expr)[prefix_len:] for r in replies if r.ok is not None)

    def watch_alive(self, key: str, on_change: Callable[[str, bool], None]) -> Any:
        """Call ``on_change(relative_key, alive)`` when tokens under ``key`` appear or vanish."""
        prefix_len = len(self.prefix)

        def on_sample(sample: zenoh.Sample) -> None:
            try:
                on_change(
                    str(sample.key_expr)[prefix_len:],
                    sample.kind == zenoh.SampleKind.PUT,
                )
            except Exception:
                _log().exception("liveliness handler for %s failed", key)

        subscriber = self._session.liveliness().declare_subscriber(
            self.key(key), on_sample, history=True
        )
        with self._lock:
            self._declared.append(subscriber)
        return subscriber


RETRY = 1.0  # seconds between attempts to reach the executive


def connect_when_there(
    connect: Callable[[], Bus], endpoint: str, stop: threading.Event, say: Callable[[str], None]
) -> Bus | None:
    """Call ``connect`` every :data:`RETRY` seconds until it opens a session (the
    executive listens at ``endpoint``); ``None`` if ``stop`` is set first. Tells ``say``
    once why it waits."""
    said = False
    while not stop.is_set():
        try:
            return connect()
        except BusError as e:
            if not said:
                say(f"waiting for the executive at {endpoint} ({e})")
                said = True
            stop.wait(RETRY)
    return None


def _short(error: Exception) -> str:
    """A zenoh error without its Rust source location."""
    return str(error).split(" at /")[0].strip().rstrip("!.")
