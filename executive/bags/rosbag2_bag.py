"""rosbag2 bags read with ``rosbags``: sqlite3 storage (``.db3``), and folders whose files
are compressed (MCAP folders are read by :mod:`executive.bags.mcap_bag`, which keeps
the publish times).

A sqlite3 bag records when each message was received, not when it was sent; message
definitions come from the bag (rosbag2 stores them since Jazzy) or from ``rosbags``'
type store of the bag's ROS distribution.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator, Mapping
from dataclasses import dataclass, field
from pathlib import Path

from rosbags.interfaces import Connection, MessageDefinitionFormat
from rosbags.rosbag2 import Reader

from executive.bags.bag import Bag, BagTopic, Route
from executive.bags.ros_messages import Definition, RosTypes
from executive.bus.session import Message
from executive.ros2.message import RosMessage
from knowledge.errors import BagError


def _reason(error: BaseException) -> str:
    text = str(error).strip()
    return f"{type(error).__name__}: {text}" if text else type(error).__name__


@dataclass
class RosbagsBag(Bag):
    """A rosbag2 bag that ``rosbags`` reads."""

    reader: Reader | None = None
    connections: tuple[Connection, ...] = ()
    distro: str | None = None
    _types: RosTypes | None = field(default=None, repr=False)

    def close(self) -> None:
        if self.reader is not None and self.reader.is_open:
            self.reader.close()

    def _ros_types(self) -> RosTypes:
        if self._types is None:
            formats = {
                MessageDefinitionFormat.MSG: "ros2msg",
                MessageDefinitionFormat.IDL: "ros2idl",
            }
            definitions = {
                c.msgtype: Definition(c.msgtype, formats[c.msgdef.format], c.msgdef.data)
                for c in self.connections
                if c.msgdef.format in formats and c.msgdef.data
            }
            self._types = RosTypes(definitions.values(), self.distro, str(self.path))
        return self._types

    def check(self, routes: Mapping[str, Route]) -> None:
        types = self._ros_types()
        for connection in self.connections:
            if connection.topic in routes and not types.knows(connection.msgtype):
                raise BagError(
                    f"{self.path}: unknown message type '{connection.msgtype}' of topic "
                    f"'{connection.topic}' (the bag does not define it and rosbags' "
                    f"{types.store.name.lower()} types do not know it)"
                )

    def messages(
        self, routes: Mapping[str, Route], start: float | None = None, end: float | None = None
    ) -> Iterator[Message]:
        self.check(routes)
        if self.reader is None:
            raise BagError(f"{self.path}: the bag is closed")
        types = self._ros_types()
        makers: dict[int, Callable[[bytes, int], Message]] = {}
        chosen = [c for c in self.connections if c.topic in routes]
        for connection in chosen:
            makers[connection.id] = _maker(routes[connection.topic], types, connection.msgtype)
        found = self.reader.messages(
            chosen,
            start=None if start is None else round(start * 1e9),
            stop=None if end is None else round(end * 1e9) + 1,
        )
        while True:
            try:
                connection, timestamp, raw = next(found)
            except StopIteration:
                return
            except Exception as e:  # a cut or corrupt database fails in many ways
                raise BagError(f"{self.path}: truncated or corrupt ({_reason(e)})") from e
            yield makers[connection.id](bytes(raw), timestamp)


def _maker(route: Route, types: RosTypes, msgtype: str) -> Callable[[bytes, int], Message]:
    key, caller, decoder = route.key, route.caller, types.decoder(msgtype)

    def make(raw: bytes, timestamp: int) -> Message:
        return RosMessage(key, raw, caller, None, timestamp / 1e9, decode=decoder)

    return make


def open_rosbags(path: Path, *, file: bool = False) -> RosbagsBag:
    """Open a rosbag2 folder or (``file``) a sqlite3 file with ``rosbags``.

    Raises:
        BagError: it is not a bag ``rosbags`` can read, or it is truncated or corrupt.
    """
    try:
        reader = Reader(path)
        reader.open()
    except Exception as e:  # rosbags and sqlite3 fail in many ways on a bad file
        what = "truncated or corrupt" if file else "not a readable rosbag2"
        raise BagError(f"{path}: {what} ({_reason(e)})") from e
    try:
        connections = tuple(reader.connections)
        storage = "sqlite3" if path.suffix == ".db3" or _stored_in(path, "sqlite3") else "rosbags"
        topics = tuple(
            BagTopic(name, info.msgtype or "?", info.msgcount)
            for name, info in sorted(reader.topics.items())
        )
        count = reader.message_count
        start = reader.start_time / 1e9 if count else 0.0
        end = (reader.end_time - 1) / 1e9 if count else 0.0
        distro = reader.ros_distro
    except Exception as e:
        reader.close()
        raise BagError(f"{path}: truncated or corrupt ({_reason(e)})") from e
    return RosbagsBag(
        path=path,
        format=f"rosbag2 ({storage})",
        start=start,
        end=end,
        topics=topics,
        reader=reader,
        connections=connections,
        distro=distro,
    )


def _stored_in(path: Path, storage: str) -> bool:
    metadata = path / "metadata.yaml"
    return metadata.is_file() and f"storage_identifier: {storage}" in metadata.read_text()
