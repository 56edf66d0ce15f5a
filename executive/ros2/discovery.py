"""The ROS 2 graph: which node publishes and subscribes what, learnt as ROS 2 learns it.

DDS discovery knows participants and their readers and writers (Cyclone's built-in
topics: GUIDs, DDS topic and type names) but nothing of nodes. ROS 2 adds the nodes
on its own topic, ``ros_discovery_info``: every participant publishes (reliable,
transient local) a ``rmw_dds_common/msg/ParticipantEntitiesInfo`` listing its nodes,
each with the gids of its readers and writers. A gid is the entity's DDS GUID (16
bytes), padded with zeros to 24 bytes before Iron. Matching the two gives the node of
every endpoint: the caller id of every received sample (by its writer) and the graph
the diagnosis model needs.

A sample of ``ros_discovery_info`` is decoded with the configured distribution's
layout, and with the other gid size if that does not fit exactly, so that a robot on
Humble and dura set to Jazzy (or the reverse) still understand each other.

dura is a node of the graph too: it publishes its own entry, with the readers and
writers given to :meth:`Discovery.declare`, so ``ros2 node list`` shows it. Everything here is updated on the
participant's receive thread; the graph is read from any thread.
"""

from __future__ import annotations

import logging
import threading
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any

from rosbags.interfaces import Nodetype

from executive.ros2.cdr import CdrError, Decoder
from executive.ros2.names import (
    DISCOVERY_TOPIC,
    DISCOVERY_TYPE,
    caller_id,
    node_name,
    ros_topic,
)
from executive.ros2.participant import Announcement, Participant
from executive.ros2.qos import DISCOVERY, DISCOVERY_READER, dds_qos
from executive.ros2.types import TypeLibrary

log = logging.getLogger("dura.ros2")

INFRASTRUCTURE = frozenset({"/rosout", "/parameter_events"})  # every node has these


@dataclass(frozen=True)
class Endpoint:
    """A DDS reader or writer somebody in the domain has."""

    guid: bytes
    participant: bytes
    topic: str  # the DDS topic, e.g. rt/scan
    type: str  # the DDS type, e.g. sensor_msgs::msg::dds_::LaserScan_


@dataclass(frozen=True)
class NodeInfo:
    """A ROS 2 node and the ROS 2 topics it publishes and subscribes, sorted."""

    name: str  # fully qualified: /namespace/name
    publishes: tuple[str, ...]
    subscribes: tuple[str, ...]


def gid_layouts(library: TypeLibrary) -> list[tuple[int, Decoder]]:
    """Make decoders of ``ParticipantEntitiesInfo`` for both gid sizes, the distribution's first."""
    defs = {n: library.store.fielddefs[n] for n in ("rmw_dds_common/msg/Gid",
            "rmw_dds_common/msg/NodeEntitiesInfo", DISCOVERY_TYPE)}  # fmt: skip
    size = int(defs["rmw_dds_common/msg/Gid"][1][0][1][1][1])
    layouts = []
    for gid in (size, 24 if size == 16 else 16):
        char = (Nodetype.BASE, ("char", 0))
        gid_def: tuple[list[Any], list[Any]] = ([], [("data", (Nodetype.ARRAY, (char, gid)))])
        layouts.append((gid, Decoder({**defs, "rmw_dds_common/msg/Gid": gid_def}, DISCOVERY_TYPE)))
    return layouts


NodeEntry = tuple[str, list[bytes], list[bytes]]  # a node, its readers' and writers' GUIDs


def read_entities_info(
    data: bytes, layouts: list[tuple[int, Decoder]]
) -> tuple[int, bytes, list[NodeEntry]]:
    """Read a ``ros_discovery_info`` sample: the gid size that fits, the participant, its nodes.

    Raises:
        CdrError: no layout fits the bytes exactly.
    """
    problems = []
    for gid_size, decoder in layouts:
        try:
            value = decoder.exact(data)
        except CdrError as e:
            problems.append(str(e))
            continue

        def gid(item: dict[str, Any]) -> bytes:
            return bytes(item["data"][:16])  # a GUID, padded to 24 bytes before Iron

        nodes = [
            (
                node_name(n["node_namespace"], n["node_name"]),
                [gid(g) for g in n["reader_gid_seq"]],
                [gid(g) for g in n["writer_gid_seq"]],
            )
            for n in value["node_entities_info_seq"]
        ]
        return gid_size, gid(value["gid"]), nodes
    raise CdrError(problems[0])


class Discovery:
    """The ROS 2 graph of a domain, from one participant's view."""

    def __init__(
        self,
        participant: Participant,
        library: TypeLibrary,
        *,
        node: str = "dura",
        aliases: Mapping[str, str] | None = None,
    ) -> None:
        self.participant = participant
        self.library = library
        self.node = node_name("/", node)
        self.aliases = dict(aliases or {})  # node -> caller id (a component's name)
        self._lock = threading.Lock()
        self._announcing = threading.Lock()  # one announcement at a time, the newest last
        self._writers: dict[bytes, Endpoint] = {}
        self._readers: dict[bytes, Endpoint] = {}
        self._handles: dict[int, bytes] = {}  # publication instance handle -> writer GUID
        self._nodes: dict[bytes, list[NodeEntry]] = {}  # by participant
        self._node_of: dict[bytes, str] = {}  # endpoint GUID -> node
        self._callers: dict[int, str] = {}  # publication handle -> caller id, once known
        self._own_readers: dict[bytes, None] = {}  # dura's, in the order declared
        self._own_writers: dict[bytes, None] = {}
        self._listeners: list[Callable[[], None]] = []
        self._layouts = gid_layouts(library)
        self._gid_size = self._layouts[0][0]
        self._warned: set[str] = set()
        info_type = library.idl(DISCOVERY_TYPE)
        self._writer = participant.writer(DISCOVERY_TOPIC, info_type, dds_qos(DISCOVERY))
        self._entities = [
            participant.builtin_reader("participant", self._on_participants),
            participant.builtin_reader("publication", self._on_writers),
            participant.builtin_reader("subscription", self._on_readers),
            participant.reader(
                DISCOVERY_TOPIC,
                info_type,
                dds_qos(DISCOVERY_READER, ignore_local=True),
                self._on_info,
                first=True,
            ),
        ]
        self._announce()

    # --- what the rest of dura asks -------------------------------------------------

    def caller(self, publication_handle: int) -> str:
        """Name a sample's writer as a caller id: the component its node is (an alias),
        its node (``robot1/lidar``), else ``dds:<guid>``."""
        found = self._callers.get(publication_handle)
        if found is not None:
            return found
        guid = self._handles.get(publication_handle)
        if guid is None:
            return f"dds:{publication_handle:x}"
        node = self._node_of.get(guid)
        if node is None:
            return f"dds:{guid.hex()}"
        found = self.aliases.get(node) or caller_id(node)
        self._callers[publication_handle] = found
        return found

    def node_of(self, guid: bytes) -> str | None:
        """Return the node (``/ns/name``) of a reader or writer, if ROS 2 told."""
        with self._lock:
            return self._node_of.get(guid)

    def nodes(self, *, everything: bool = False) -> dict[str, NodeInfo]:
        """List every node of the domain with its topics.

        ``/rosout`` and ``/parameter_events`` (every node has them) only with ``everything``.
        """
        with self._lock:
            out: dict[str, tuple[set[str], set[str]]] = {}
            for entries in self._nodes.values():
                for name, readers, writers in entries:
                    pubs, subs = out.setdefault(name, (set(), set()))
                    pubs.update(self._topics(writers, self._writers, everything))
                    subs.update(self._topics(readers, self._readers, everything))
        return {n: NodeInfo(n, tuple(sorted(p)), tuple(sorted(s))) for n, (p, s) in out.items()}

    @staticmethod
    def _topics(gids: list[bytes], known: dict[bytes, Endpoint], everything: bool) -> set[str]:
        found = {ros_topic(known[g].topic) for g in gids if g in known}
        return {t for t in found if t is not None and (everything or t not in INFRASTRUCTURE)}

    def types_of(self, topic: str) -> set[str]:
        """Return the DDS type names the writers of a ROS 2 topic (``/scan``) use."""
        with self._lock:
            return {e.type for e in self._writers.values() if ros_topic(e.topic) == topic}

    def on_change(self, listener: Callable[[], None]) -> None:
        """Call ``listener`` (on the receive thread) after every change of the graph."""
        with self._lock:
            self._listeners.append(listener)

    def declare(self, guid: bytes, *, writer: bool) -> None:
        """Count a reader or writer of dura's as its node's, and tell the graph."""
        with self._lock:
            (self._own_writers if writer else self._own_readers)[guid] = None
        self._announce()

    def retract(self, guid: bytes) -> None:
        """Forget a reader or writer of dura's (deleted), and tell the graph."""
        with self._lock:
            self._own_writers.pop(guid, None)
            self._own_readers.pop(guid, None)
        self._announce()

    def _announce(self) -> None:
        """Publish dura's node with its readers and writers on ``ros_discovery_info``."""
        own = self.participant.guid
        with self._announcing:
            with self._lock:
                entry = (self.node, list(self._own_readers), list(self._own_writers))
                self._nodes[own] = [entry]
                self._reindex()
            self._write_info(own, entry)

    def _write_info(self, own: bytes, entry: NodeEntry) -> None:
        pad = bytes(self._gid_size - 16)
        self._writer.write(
            self.library.create(
                DISCOVERY_TYPE,
                {
                    "gid": {"data": list(own + pad)},
                    "node_entities_info_seq": [
                        {
                            "node_namespace": "/",
                            "node_name": self.node.rpartition("/")[2],
                            "reader_gid_seq": [{"data": list(g + pad)} for g in entry[1]],
                            "writer_gid_seq": [{"data": list(g + pad)} for g in entry[2]],
                        }
                    ],
                },
            )
        )

    # --- updates, on the receive thread ---------------------------------------------

    def _on_participants(self, found: list[Announcement], received: float) -> None:
        with self._lock:
            for participant in found:
                if not participant.alive and self._nodes.pop(participant.guid, None) is not None:
                    self._reindex()
        self._changed()

    def _on_writers(self, found: list[Announcement], received: float) -> None:
        with self._lock:
            for writer in found:
                if writer.alive:
                    self._writers[writer.guid] = _endpoint(writer)
                    self._handles[writer.handle] = writer.guid
                else:
                    self._writers.pop(writer.guid, None)
                    self._handles.pop(writer.handle, None)
                    self._callers.pop(writer.handle, None)
        self._changed()

    def _on_readers(self, found: list[Announcement], received: float) -> None:
        with self._lock:
            for reader in found:
                if reader.alive:
                    self._readers[reader.guid] = _endpoint(reader)
                else:
                    self._readers.pop(reader.guid, None)
        self._changed()

    def _on_info(self, samples: list[Any], received: float) -> None:
        for data, info in samples:
            if not info.valid_data:
                continue
            entries = self._read_info(data)
            if entries is None:
                continue
            participant, nodes = entries
            with self._lock:
                self._nodes[participant] = nodes
                self._reindex()
        self._changed()

    def _read_info(self, data: bytes) -> tuple[bytes, list[NodeEntry]] | None:
        """Read a participant and its nodes from a ``ros_discovery_info`` sample (None: malformed)."""
        try:
            gid_size, participant, nodes = read_entities_info(data, self._layouts)
        except CdrError as e:
            log.warning("ignored a malformed ros_discovery_info sample: %s", e)
            return None
        if gid_size != self._gid_size:
            self._warn_once(
                f"gid{gid_size}",
                f"ros_discovery_info comes with {gid_size}-byte gids, not the "
                f"{self._gid_size} of ROS 2 {self.library.distribution}; understood anyway",
            )
        return participant, nodes

    def _reindex(self) -> None:
        self._node_of = {
            gid: name
            for entries in self._nodes.values()
            for name, readers, writers in entries
            for gid in (*readers, *writers)
        }
        self._callers = {}

    def _changed(self) -> None:
        for listener in list(self._listeners):
            try:
                listener()
            except Exception:
                log.exception("a ROS 2 graph listener failed")

    def _warn_once(self, key: str, message: str) -> None:
        if key not in self._warned:
            self._warned.add(key)
            log.warning("%s", message)

    def close(self) -> None:
        """Delete the discovery readers and writer (the participant stays)."""
        for entity in self._entities:
            entity.close()
        self._writer.close()


def _endpoint(found: Announcement) -> Endpoint:
    return Endpoint(found.guid, found.participant, found.topic, found.type)
