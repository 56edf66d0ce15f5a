"""A small kit of ROS 2 nodes on plain Cyclone DDS, speaking ROS 2's wire conventions.

The stand-in nodes of the example use it in place of rclpy (which needs a ROS
installation): a :class:`Node` is one DDS participant that announces its node, with
its readers' and writers' gids, on ``ros_discovery_info`` as every ROS 2 process does;
topics are ``rt/<name>``; a service ``/x`` is ``rq/xRequest`` and ``rr/xReply`` with
rmw_cyclonedds' request header (``guid_``, ``seq_``) before the message; an
:class:`ActionServer` serves ``send_goal``, ``get_result`` and ``cancel_goal`` and
publishes ``feedback`` and ``status`` as rcl_action does; a :class:`LifecycleNode`
serves ``get_state`` and ``change_state`` and publishes ``transition_event`` with
rcl_lifecycle's states and transitions (:mod:`.action_server`, :mod:`.lifecycle_node`).

It shares no code with dura, so that dura's tests against these nodes check dura
against an independent rendering of the conventions.
"""

from __future__ import annotations

import json
import os
import threading
import time
from collections.abc import Callable
from typing import Any

from cyclonedds.core import (
    Entity,
    InstanceState,
    Policy,
    Qos,
    ReadCondition,
    SampleState,
    ViewState,
    WaitSet,
)
from cyclonedds.domain import DomainParticipant
from cyclonedds.idl import IdlStruct
from cyclonedds.internal import DDS
from cyclonedds.pub import DataWriter
from cyclonedds.sub import DataReader
from cyclonedds.topic import Topic
from cyclonedds.util import duration

from . import interfaces as ros

FOREVER = duration(infinite=True)
ANY = SampleState.Any | ViewState.Any | InstanceState.Any
Handler = Callable[[Any], None]


def qos(
    *, reliable: bool = True, depth: int = 10, latched: bool = False, user_data: bytes = b""
) -> Qos:
    """Make the DDS QoS rmw_cyclonedds gives a ROS 2 endpoint."""
    policies = [
        Policy.History.KeepLast(depth),
        Policy.Reliability.Reliable(FOREVER) if reliable else Policy.Reliability.BestEffort,
        Policy.Durability.TransientLocal if latched else Policy.Durability.Volatile,
        Policy.WriterDataLifecycle(autodispose=False),
        Policy.DataRepresentation(use_cdrv0_representation=True),
    ]
    if user_data:
        policies.append(Policy.Userdata(data=user_data))
    return Qos(*policies)


def now() -> ros.Time:
    t = time.time()
    return ros.Time(sec=int(t), nanosec=int((t % 1) * 1e9))


def params() -> dict[str, Any]:
    """Read the parameters dura passes a program (``DURA_PARAMS``, JSON)."""
    try:
        value = json.loads(os.environ.get("DURA_PARAMS") or "{}")
    except ValueError:
        return {}
    return value if isinstance(value, dict) else {}


def _user_data(endpoint: Any, key: str) -> str | None:
    """Read ``key=value;`` from a discovered endpoint's user data."""
    if endpoint is None or Policy.Userdata not in endpoint.qos:
        return None
    for pair in bytes(endpoint.qos[Policy.Userdata].data).decode(errors="replace").split(";"):
        name, _, value = pair.partition("=")
        if name == key:
            return value
    return None


class Node:
    """One ROS 2 node in a participant of its own; callbacks run on its spin thread."""

    def __init__(self, name: str, namespace: str = "/", domain_id: int | None = None) -> None:
        domain = int(os.environ.get("ROS_DOMAIN_ID", "0")) if domain_id is None else domain_id
        self.name, self.namespace = name, namespace
        self.participant = DomainParticipant(domain, Qos(Policy.Userdata(data=b"enclave=/;")))
        self._made: list[Entity] = [self.participant]
        self._topics: dict[str, Topic[Any]] = {}
        self._readers: list[bytes] = []
        self._writers: list[bytes] = []
        self._handlers: dict[int, tuple[DataReader[Any], Callable[[Any, Any], None]]] = {}
        self._waitset = WaitSet(self.participant)
        self._stop = threading.Event()
        self._ids = 0
        self._info = DataWriter(self.participant, self._topic("ros_discovery_info",
                                ros.ParticipantEntitiesInfo), qos(depth=1, latched=True))  # fmt: skip
        self._made.append(self._info)
        self._thread = threading.Thread(target=self._spin, daemon=True, name=f"spin-{name}")

    @property
    def full_name(self) -> str:
        return f"{self.namespace.rstrip('/')}/{self.name}"

    def _topic(self, name: str, kind: type[IdlStruct]) -> Topic[Any]:
        if name not in self._topics:
            self._topics[name] = Topic(self.participant, name, kind)
            self._made.append(self._topics[name])
        return self._topics[name]

    def writer(self, dds_topic: str, kind: type[IdlStruct], with_qos: Qos) -> DataWriter[Any]:
        """Make a writer of a DDS topic that belongs to this node."""
        writer = DataWriter(self.participant, self._topic(dds_topic, kind), with_qos)
        self._made.append(writer)
        self._writers.append(writer.guid.bytes)
        return writer

    def reader(
        self,
        dds_topic: str,
        kind: type[IdlStruct],
        with_qos: Qos,
        handler: Callable[[Any, Any], None],
    ) -> DataReader[Any]:
        """Make a reader of a DDS topic; ``handler(sample, info)`` gets each sample."""
        reader = DataReader(self.participant, self._topic(dds_topic, kind), with_qos)
        condition = ReadCondition(reader, ANY)
        self._waitset.attach(condition)
        self._made += [reader, condition]
        self._readers.append(reader.guid.bytes)
        self._handlers[reader._ref] = (reader, handler)
        return reader

    def publisher(self, topic: str, kind: type[IdlStruct], **options: Any) -> DataWriter[Any]:
        return self.writer("rt" + topic, kind, qos(**options))

    def subscription(
        self, topic: str, kind: type[IdlStruct], handler: Handler, **options: Any
    ) -> None:
        self.reader("rt" + topic, kind, qos(**options), lambda sample, info: handler(sample))

    def service(
        self,
        name: str,
        request: type[IdlStruct],
        response: type[IdlStruct],
        handler: Callable[[Any], dict[str, Any]],
    ) -> None:
        """Serve ``name``: ``handler(request)`` returns the response's fields."""
        self._ids += 1
        serviceid = f"serviceid={self.participant.guid.bytes[:12].hex()}.{self._ids};".encode()
        replies = self.writer(f"rr{name}Reply", response, qos(user_data=serviceid))
        requests: DataReader[Any]

        def answer(sample: Any, info: Any) -> None:
            fields = handler(sample)
            writer = requests.get_matched_publication_data(info.publication_handle)
            _wait_for_client(replies, _user_data(writer, "clientid"))
            replies.write(response(guid_=sample.guid_, seq_=sample.seq_, **fields))

        requests = self.reader(f"rq{name}Request", request, qos(user_data=serviceid), answer)

    def announce(self) -> None:
        """Publish this node with its endpoints on ``ros_discovery_info``."""
        self._info.write(
            ros.ParticipantEntitiesInfo(
                gid=ros.Gid(data=list(self.participant.guid.bytes)),
                node_entities_info_seq=[
                    ros.NodeEntitiesInfo(
                        node_namespace=self.namespace,
                        node_name=self.name,
                        reader_gid_seq=[ros.Gid(data=list(g)) for g in self._readers],
                        writer_gid_seq=[ros.Gid(data=list(g)) for g in self._writers],
                    )
                ],
            )
        )

    def start(self) -> None:
        """Announce the node and spin (serve its readers) on a thread."""
        self.announce()
        self._thread.start()

    def _spin(self) -> None:
        while not self._stop.is_set():
            self._waitset.wait(duration(milliseconds=50))
            for reader, handler in list(self._handlers.values()):
                for sample in reader.take(N=64):
                    info = sample.sample_info
                    if info.valid_data:
                        handler(sample, info)

    def run_until_stopped(self) -> None:
        """Start, then wait for SIGTERM or SIGINT (what dura sends to stop a program)."""
        import signal

        for signum in (signal.SIGTERM, signal.SIGINT):
            signal.signal(signum, lambda *_: self._stop.set())
        self.start()
        while not self._stop.wait(0.2):
            pass
        self.close()

    def close(self) -> None:
        """Delete the participant and everything in it."""
        self._stop.set()
        if self._thread.is_alive() and self._thread is not threading.current_thread():
            self._thread.join()
        if not self._made:
            return
        for entity in self._made:
            Entity._entities.pop(entity._ref, None)  # deleted below, not by the collector
        DDS._dll_handle.dds_delete(self.participant._ref)
        self._made.clear()


def _wait_for_client(replies: DataWriter[Any], clientid: str | None, limit: float = 0.1) -> None:
    """Wait until the reply writer has matched the reader of the client (rmw_cyclonedds
    waits 100 ms for it); a client without an id is assumed to be there."""
    if clientid is None:
        return
    deadline = time.monotonic() + limit
    while time.monotonic() < deadline:
        for handle in replies.get_matched_subscriptions():
            if _user_data(replies.get_matched_subscription_data(handle), "clientid") == clientid:
                return
        time.sleep(0.01)
