"""The other side of the ROS 2 tests: a plain Cyclone DDS participant that acts on the
wire as a ROS 2 process with some nodes does (rmw_cyclonedds' conventions).

It uses none of dura's ROS 2 code: its types are written out by hand
(:mod:`tests.executive.ros2.messages`), its topics are ``rt/<name>``, its QoS are set
here, and it publishes its nodes and their readers' and writers' gids on
``ros_discovery_info`` (reliable, transient local, keep last 1), as every ROS 2
participant does.

In a test process: ``with RosPeer(domain) as peer: peer.publisher("lidar", "/scan",
LaserScan)``. As a process of its own (real UDP between processes)::

    python -m tests.executive.ros2.peer DOMAIN PLAN_JSON

PLAN is ``{"streams": [{"node": "lidar", "topic": "/scan", "rate": 20}]}`` (LaserScan
messages stamped now); it prints ``ready`` once its nodes are announced and runs until
its stdin closes.
"""

from __future__ import annotations

import contextlib
import json
import sys
import threading
import time
from collections.abc import Iterator
from typing import Any

from cyclonedds.core import Entity, Policy, Qos
from cyclonedds.domain import DomainParticipant
from cyclonedds.idl import IdlStruct
from cyclonedds.internal import DDS
from cyclonedds.pub import DataWriter
from cyclonedds.sub import DataReader
from cyclonedds.topic import Topic
from cyclonedds.util import duration

from tests.executive.ros2.messages import (
    Gid,
    Header,
    LaserScan,
    NodeEntitiesInfo,
    ParticipantEntitiesInfo,
    Time,
)

FOREVER = duration(infinite=True)

# Cyclone DDS on loopback only, no multicast: discovery by unicast to 127.0.0.1
LOOPBACK = """\
<CycloneDDS xmlns="https://cdds.io/config">
  <Domain id="any">
    <General>
      <Interfaces><NetworkInterface address="127.0.0.1" multicast="false"/></Interfaces>
      <AllowMulticast>false</AllowMulticast>
    </General>
    <Discovery>
      <ParticipantIndex>auto</ParticipantIndex>
      <MaxAutoParticipantIndex>40</MaxAutoParticipantIndex>
      <Peers><Peer address="127.0.0.1"/></Peers>
    </Discovery>
  </Domain>
</CycloneDDS>
"""


def ros_qos(*, reliable: bool = True, depth: int = 10, latched: bool = False) -> Qos:
    """The DDS QoS rmw_cyclonedds gives a ROS 2 endpoint."""
    return Qos(
        Policy.History.KeepLast(depth),
        Policy.Reliability.Reliable(FOREVER) if reliable else Policy.Reliability.BestEffort,
        Policy.Durability.TransientLocal if latched else Policy.Durability.Volatile,
        Policy.WriterDataLifecycle(autodispose=False),
        Policy.DataRepresentation(use_cdrv0_representation=True),
    )


def stamp(now: float | None = None) -> Time:
    now = time.time() if now is None else now
    return Time(sec=int(now), nanosec=int((now % 1) * 1e9))


class RosPeer:
    """A ROS 2 process as DDS sees it: one participant, some nodes, their endpoints."""

    def __init__(self, domain_id: int) -> None:
        self.participant = DomainParticipant(domain_id, Qos(Policy.Userdata(b"enclave=/;")))
        self._made: list[Entity] = [self.participant]
        self._topics: dict[str, Topic[Any]] = {}
        self._nodes: dict[tuple[str, str], tuple[list[bytes], list[bytes]]] = {}
        self._info = self._writer("ros_discovery_info", ParticipantEntitiesInfo,
                                  ros_qos(depth=1, latched=True))  # fmt: skip

    def _topic(self, name: str, kind: type[IdlStruct]) -> Topic[Any]:
        if name not in self._topics:
            self._topics[name] = Topic(self.participant, name, kind)
            self._made.append(self._topics[name])
        return self._topics[name]

    def _writer(self, name: str, kind: type[IdlStruct], qos: Qos) -> DataWriter[Any]:
        writer = DataWriter(self.participant, self._topic(name, kind), qos)
        self._made.append(writer)
        return writer

    def node(self, name: str, namespace: str = "/") -> None:
        """Add a node (no endpoints yet) and announce it."""
        self._nodes.setdefault((namespace, name), ([], []))
        self.announce()

    def publisher(
        self, node: str, topic: str, kind: type[IdlStruct], *, namespace: str = "/", **qos: Any
    ) -> DataWriter[Any]:
        """A writer on ``rt<topic>`` that belongs to ``node``."""
        writer = self._writer("rt" + topic, kind, ros_qos(**qos))
        self._nodes.setdefault((namespace, node), ([], []))[1].append(writer.guid.bytes)
        self.announce()
        return writer

    def subscriber(
        self, node: str, topic: str, kind: type[IdlStruct], *, namespace: str = "/", **qos: Any
    ) -> DataReader[Any]:
        """A reader of ``rt<topic>`` that belongs to ``node``."""
        reader = DataReader(self.participant, self._topic("rt" + topic, kind), ros_qos(**qos))
        self._made.append(reader)
        self._nodes.setdefault((namespace, node), ([], []))[0].append(reader.guid.bytes)
        self.announce()
        return reader

    def reader(self, name: str, kind: type[IdlStruct], qos: Qos) -> DataReader[Any]:
        """A reader of a DDS topic by its DDS name, of no node."""
        reader = DataReader(self.participant, self._topic(name, kind), qos)
        self._made.append(reader)
        return reader

    def announce(self) -> None:
        """Publish this participant's nodes on ``ros_discovery_info``."""

        def gid(raw: bytes) -> Gid:
            return Gid(data=list(raw))

        self._info.write(
            ParticipantEntitiesInfo(
                gid=gid(self.participant.guid.bytes),
                node_entities_info_seq=[
                    NodeEntitiesInfo(
                        node_namespace=namespace,
                        node_name=name,
                        reader_gid_seq=[gid(g) for g in readers],
                        writer_gid_seq=[gid(g) for g in writers],
                    )
                    for (namespace, name), (readers, writers) in self._nodes.items()
                ],
            )
        )

    def close(self) -> None:
        """Delete the participant and everything in it, now."""
        if not self._made:
            return
        for entity in self._made:
            Entity._entities.pop(entity._ref, None)  # deleted below, not by the collector
        DDS._dll_handle.dds_delete(self.participant._ref)
        self._made.clear()

    def __enter__(self) -> RosPeer:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


def scan(now: float | None = None, ranges: list[float] | None = None) -> LaserScan:
    """A laser scan stamped ``now``."""
    return LaserScan(
        header=Header(stamp=stamp(now), frame_id="laser"),
        angle_min=-1.0, angle_max=1.0, angle_increment=0.5, range_min=0.1, range_max=10.0,
        ranges=ranges if ranges is not None else [1.0, 2.0, 3.0, 4.0, 5.0],
    )  # fmt: skip


@contextlib.contextmanager
def streaming(writer: DataWriter[Any], rate: float, make: Any = scan) -> Iterator[None]:
    """Write ``make()`` at ``rate`` Hz on a thread while the block runs."""
    stop = threading.Event()

    def run() -> None:
        due = time.monotonic()
        while not stop.is_set():
            writer.write(make())
            due += 1.0 / rate
            stop.wait(max(0.0, due - time.monotonic()))

    thread = threading.Thread(target=run, daemon=True)
    thread.start()
    try:
        yield
    finally:
        stop.set()
        thread.join()


def main() -> None:
    domain, plan = int(sys.argv[1]), json.loads(sys.argv[2])
    with RosPeer(domain) as peer, contextlib.ExitStack() as streams:
        for stream in plan["streams"]:
            writer = peer.publisher(stream["node"], stream["topic"], LaserScan)
            streams.enter_context(streaming(writer, float(stream["rate"])))
        print("ready", flush=True)
        sys.stdin.read()  # until the test closes our stdin


if __name__ == "__main__":
    main()
