"""A client of one ROS 2 service over DDS, with the request header of rmw_cyclonedds.

A service ``/reset`` is two DDS topics, ``rq/resetRequest`` and ``rr/resetReply``. On
the wire (rmw_cyclonedds' serdata) a request is the CDR encapsulation, the client's id
(uint64: the instance handle of its request writer), the request's sequence number
(int64), then the request message; the reply repeats both numbers before the response.
A client keeps the replies that carry its own id and pairs them with its requests by
sequence number. Both halves of a client say ``clientid=<id>;`` in their user data:
an rmw_cyclonedds server then waits until it has matched the reader of the client that
sent a request before it replies, so that no reply is lost to a discovery in progress.

A client is ready when its request writer has matched a reader and its reply reader a
writer. rmw_fastrtps carries the request id outside the message (in the RTPS inline
QoS): its services do not understand these requests.
"""

from __future__ import annotations

import itertools
import struct
import threading
import time
from collections.abc import Mapping
from concurrent.futures import Future
from concurrent.futures import TimeoutError as FutureTimeout
from typing import Any

from executive.ros2.cdr import CdrError
from executive.ros2.discovery import Discovery
from executive.ros2.names import reply_topic, request_topic
from executive.ros2.participant import Participant
from executive.ros2.qos import dds_qos
from executive.ros2.types import TypeLibrary
from knowledge.errors import BusError
from knowledge.ros2_spec import PROFILES

HEADER_SIZE = 16  # uint64 client id, int64 sequence number
_ORDERS = {b"\x00\x00": ">", b"\x00\x01": "<"}  # CDR_BE, CDR_LE
POLL = 0.01  # seconds between two looks at the matches


def _order(data: bytes) -> str:
    order = _ORDERS.get(bytes(data[:2]))
    if order is None or len(data) < 4:
        raise CdrError(f"not plain CDR (encapsulation {bytes(data[:4]).hex() or 'missing'})")
    return order


def wrap(message: bytes, guid: int, seq: int) -> bytes:
    """Put the request header (client id, sequence number) before a serialised message.

    The message keeps its alignment: the header is 16 bytes, a multiple of every
    alignment CDR knows.
    """
    return message[:4] + struct.pack(_order(message) + "Qq", guid, seq) + message[4:]


def unwrap(data: bytes) -> tuple[int, int, bytes]:
    """Split a request or reply into client id, sequence number and the message's bytes.

    Raises:
        CdrError: not CDR, or too short for the header.
    """
    order = _order(data)
    if len(data) < 4 + HEADER_SIZE:
        raise CdrError(f"{len(data)} bytes: too short for a request header")
    guid, seq = struct.unpack_from(order + "Qq", data, 4)
    return guid, seq, bytes(data[:4]) + bytes(data[4 + HEADER_SIZE :])


def endpoint_id(guid: bytes) -> str:
    """Write a DDS GUID as rmw_cyclonedds writes client and service ids: hex bytes, dotted."""
    return ".".join(f"{b:02x}" if i == 0 else f"{b:x}" for i, b in enumerate(guid))


class ServiceClient:
    """Calls one ROS 2 service: requests out, each reply back to its caller.

    Args:
        participant: the DDS participant to call from.
        library: the message types (``<type>_Request``, ``<type>_Response``).
        service: the service's name, e.g. ``/lidar/change_state``.
        service_type: e.g. ``lifecycle_msgs/srv/ChangeState``.
        discovery: when given, the client's reader and writer are dura's node's.

    Raises:
        ConfigError: an unknown service type.
        BusError: DDS refused an endpoint.
    """

    def __init__(
        self,
        participant: Participant,
        library: TypeLibrary,
        service: str,
        service_type: str,
        *,
        discovery: Discovery | None = None,
    ) -> None:
        self.service = service
        self.library = library
        self.request_type = library.check(f"{service_type}_Request")
        self.response_type = library.check(f"{service_type}_Response")
        self._decoder = library.decoder(self.response_type)
        self._lock = threading.Lock()
        self._pending: dict[int, Future[dict[str, Any]]] = {}
        self._numbers = itertools.count(1)
        self._discovery = discovery
        profile = PROFILES["services_default"]
        user_data = f"clientid={endpoint_id(participant.unique_id())};".encode()
        self._writer = participant.writer(
            request_topic(service),
            library.wrapped(self.request_type),
            dds_qos(profile, user_data=user_data),
        )
        self.guid = self._writer.instance_handle
        try:
            self._reader = participant.reader(
                reply_topic(service),
                library.wrapped(self.response_type),
                dds_qos(profile, user_data=user_data),
                self._on_replies,
            )
        except BaseException:
            self._writer.close()
            raise
        if discovery is not None:
            discovery.declare(self._writer.guid, writer=True)
            discovery.declare(self._reader.guid, writer=False)

    def ready(self) -> bool:
        """Tell whether a server is matched both ways."""
        return self._writer.matched() > 0 and self._reader.matched() > 0

    def wait(self, timeout: float) -> bool:
        """Wait until a server is there; whether it came within ``timeout`` seconds."""
        deadline = time.monotonic() + timeout
        while not self.ready():
            if time.monotonic() >= deadline:
                return False
            time.sleep(POLL)
        return True

    def call_async(self, request: Mapping[str, Any] | None = None) -> Future[dict[str, Any]]:
        """Send a request; its future gets the response as a dict.

        Raises:
            ConfigError: a field the request type does not have.
            BusError: DDS refused the request.
        """
        message = self.library.create(self.request_type, request or {}).serialize()
        future: Future[dict[str, Any]] = Future()
        with self._lock:
            seq = next(self._numbers)
            self._pending[seq] = future
        try:
            self._writer.write_raw(wrap(message, self.guid, seq))
        except BusError:
            with self._lock:
                self._pending.pop(seq, None)
            raise
        return future

    def call(self, request: Mapping[str, Any] | None = None, *, timeout: float) -> dict[str, Any]:
        """Send a request and wait for its response.

        Raises:
            BusError: no response within ``timeout`` seconds, or DDS refused the request.
        """
        future = self.call_async(request)
        try:
            return future.result(timeout)
        except FutureTimeout:
            future.cancel()
            raise BusError(
                f"ROS 2 service {self.service} did not answer within {timeout:g} s"
            ) from None

    def _on_replies(self, samples: list[Any], received: float) -> None:
        for data, info in samples:
            if not info.valid_data:
                continue
            try:
                guid, seq, message = unwrap(data)
            except CdrError:
                continue
            if guid != self.guid:
                continue  # another client's
            with self._lock:
                future = self._pending.pop(seq, None)
            if future is None or future.done():
                continue
            try:
                future.set_result(self._decoder(message))
            except CdrError as e:
                future.set_exception(BusError(f"a malformed reply of {self.service}: {e}"))

    def close(self) -> None:
        """Delete the client's endpoints; waiting callers get a BusError."""
        with self._lock:
            pending, self._pending = self._pending, {}
        for future in pending.values():
            if not future.done():
                future.set_exception(BusError(f"the client of {self.service} was closed"))
        for endpoint in (self._writer, self._reader):
            if self._discovery is not None and not self._discovery.participant.closed:
                self._discovery.retract(endpoint.guid)
            endpoint.close()
