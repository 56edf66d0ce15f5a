"""rosbag2's sqlite3 storage (``.db3`` files), read file by file with ``rosbags``, and
the zstd compression rosbag2 writes (whole files or each message) in both storages.

Each ``.db3`` file is read on its own and the files merged by time: a file's topics
are matched to the routes by name, never through ``metadata.yaml``, whose topic list
and QoS text need not agree with the files' (rosbag2's own test bags differ there, and
``rosbags`` then finds no message at all). The ``timestamp`` of a sqlite3 message is
when it was received; sqlite3 storage records no send time. The window is the first
and last message's time as the files hold them, in integer nanoseconds. Every schema
of the ``messages`` and ``topics`` tables from Foxy on is read (``rosbags`` tells them
apart); message definitions come from the file (rosbag2 stores them since Jazzy), else
from the ``--types`` files, else from ``rosbags``' type store of the bag's distribution.
"""

from __future__ import annotations

import contextlib
import heapq
import tempfile
from collections.abc import Callable, Iterator, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import zstandard
from rosbags.interfaces import Connection, MessageDefinitionFormat
from rosbags.rosbag2.storage_sqlite3 import Sqlite3Reader

from executive.bags.bag import Bag, BagTopic, Route
from executive.bags.message import ros_message
from executive.bags.ros_messages import Definition, RosTypes
from executive.bus.message import Message
from knowledge.errors import BagError

FORMATS = {MessageDefinitionFormat.MSG: "ros2msg", MessageDefinitionFormat.IDL: "ros2idl"}


def reason(error: BaseException) -> str:
    text = str(error).strip()
    return f"{type(error).__name__}: {text}" if text else type(error).__name__


def unpack_message(data: bytes) -> bytes:
    """Decompress one message of a bag compressed per message (zstd)."""
    return bytes(zstandard.ZstdDecompressor().decompressobj().decompress(data))


def uncompressed(
    files: Sequence[Path], compression: str | None
) -> tuple[list[Path], tempfile.TemporaryDirectory[str] | None, Callable[[bytes], bytes] | None]:
    """For rosbag2's compression mode: the files to read, the folder that holds them
    decompressed (remove it with the bag), and how to decompress each message.

    Raises:
        BagError: a file is not zstd or is cut short.
    """
    if compression != "file":
        return list(files), None, unpack_message if compression == "message" else None
    folder = tempfile.TemporaryDirectory(prefix="dura-bag-")
    try:
        return unpack_files(files, Path(folder.name)), folder, None
    except BaseException:
        folder.cleanup()
        raise


def unpack_files(files: Sequence[Path], into: Path) -> list[Path]:
    """Decompress the files of a bag compressed per file (``x.db3.zstd`` -> ``x.db3``).

    Raises:
        BagError: a file is not zstd or is cut short.
    """
    unpacked = []
    for path in files:
        target = into / path.name.removesuffix(".zstd")
        try:
            with path.open("rb") as source, target.open("wb") as out:
                zstandard.ZstdDecompressor().copy_stream(source, out)
        except (OSError, zstandard.ZstdError) as e:
            raise BagError(f"{path}: cannot decompress it ({reason(e)})") from e
        unpacked.append(target)
    return unpacked


@dataclass
class Sqlite3Bag(Bag):
    """rosbag2 ``.db3`` files, read as one bag."""

    readers: list[Sqlite3Reader] = field(default_factory=list)
    distro: str | None = None
    unpack: Callable[[bytes], bytes] | None = None  # messages compressed one by one
    temporary: tempfile.TemporaryDirectory[str] | None = None  # decompressed files
    extra_types: Mapping[str, Any] = field(default_factory=dict)
    _types: RosTypes | None = field(default=None, repr=False)

    def close(self) -> None:
        for reader in self.readers:
            with contextlib.suppress(Exception):  # closed already
                reader.close()
        self.readers.clear()
        if self.temporary is not None:
            self.temporary.cleanup()
            self.temporary = None

    def _ros_types(self) -> RosTypes:
        if self._types is None:
            definitions = {
                c.msgtype: Definition(c.msgtype, FORMATS[c.msgdef.format], c.msgdef.data)
                for reader in self.readers
                for c in reader.connections
                if c.msgdef.format in FORMATS and c.msgdef.data
            }
            self._types = RosTypes(definitions.values(), self.distro, self.extra_types)
        return self._types

    def messages(
        self, routes: Mapping[str, Route], start: int | None = None, end: int | None = None
    ) -> Iterator[Message]:
        if not self.readers:
            raise BagError(f"{self.path}: the bag is closed")
        streams = []
        for reader in self.readers:
            chosen = [c for c in reader.connections if c.topic in routes]
            if chosen:  # none: rosbags would read every topic
                makers = {c.id: self._maker(routes[c.topic], c) for c in chosen}
                streams.append(self._read(reader, chosen, makers, start, end))
        merged = streams[0] if len(streams) == 1 else heapq.merge(*streams, key=_time)
        for _, message in merged:
            yield message

    def _read(
        self,
        reader: Sqlite3Reader,
        chosen: list[Connection],
        makers: dict[int, Callable[[bytes, int], Message]],
        start: int | None,
        end: int | None,
    ) -> Iterator[tuple[int, Message]]:
        stop = None if end is None else end + 1
        found = reader.messages(chosen, start=start, stop=stop)
        while True:
            try:
                connection, timestamp, raw = next(found)
            except StopIteration:
                return
            except Exception as e:  # a cut or corrupt database fails in many ways
                raise BagError(f"{reader.path}: truncated or corrupt ({reason(e)})") from e
            yield timestamp, makers[connection.id](bytes(raw), timestamp)

    def _maker(self, route: Route, connection: Connection) -> Callable[[bytes, int], Message]:
        topic = connection.topic
        decoder = self._ros_types().decoder(
            connection.msgtype,
            lambda why: self.note(f"{self.path}: topic '{topic}' not decoded: {why}"),
        )
        key, caller, unpack = route.key, route.caller, self.unpack
        count = self.counter(topic)

        def make(raw: bytes, timestamp: int) -> Message:
            return ros_message(
                key,
                raw,
                caller,
                (None, timestamp),
                decode=decoder,
                on_undecodable=count,
                unpack=unpack,
            )

        return make


def _time(item: tuple[int, Message]) -> int:
    return item[0]


def open_sqlite3(
    path: Path,
    files: Sequence[Path],
    *,
    distro: str | None = None,
    compression: str = "",
    extra_types: Mapping[str, Any] | None = None,
) -> Sqlite3Bag:
    """Open rosbag2 ``.db3`` files as one bag (``path`` names it in messages).

    Args:
        compression: rosbag2's compression mode: ``file``, ``message`` or none.

    Raises:
        BagError: a file is not a database ``rosbags`` reads, or is truncated or corrupt.
    """
    bag = Sqlite3Bag(path=path, format="rosbag2 (sqlite3)", distro=distro)
    bag.extra_types = extra_types or {}
    try:
        files, bag.temporary, bag.unpack = uncompressed(files, compression)
        for name in files:
            bag.readers.append(_open_file(name))
        _read_topics(bag)
    except BaseException:
        bag.close()
        raise
    return bag


def _open_file(path: Path) -> Sqlite3Reader:
    try:
        reader = Sqlite3Reader(path)
        reader.open()
    except Exception as e:  # rosbags and sqlite3 fail in many ways on a bad file
        raise BagError(f"{path}: truncated or corrupt ({reason(e)})") from e
    return reader


def _read_topics(bag: Sqlite3Bag) -> None:
    counts: dict[str, int] = {}
    types: dict[str, set[str]] = {}
    starts, ends = [], []
    for reader in bag.readers:
        try:
            for connection in reader.connections:
                counts[connection.topic] = counts.get(connection.topic, 0) + connection.msgcount
                types.setdefault(connection.topic, set()).add(connection.msgtype)
            if reader.metadata.message_count:
                starts.append(reader.metadata.start_time)
                ends.append(reader.metadata.end_time - 1)  # rosbags: the time after the last
        except Exception as e:
            raise BagError(f"{reader.path}: truncated or corrupt ({reason(e)})") from e
    bag.start_ns = min(starts) if starts else 0
    bag.end_ns = max(ends) if ends else 0
    bag.topics = tuple(
        BagTopic(name, " | ".join(sorted(types[name])) or "?", counts[name])
        for name in sorted(counts)
    )
