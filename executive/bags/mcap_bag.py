"""MCAP files read with the ``mcap`` library: rosbag2's MCAP storage and dura's own
recordings, whole or cut off.

A channel's messages are CDR (ROS 2, typed by the channel's schema: its ``ros2msg`` or
``ros2idl`` definition, an empty one being a message without fields, else the
``--types`` files, else ``rosbags``' type store) or JSON (dura's recordings); others
are replayed for their times only. The receive time is the message's ``log_time``;
its ``publish_time`` is the send time (ROS 2 Jazzy and later record the publisher's;
older bags repeat the receive time). A dura recording (profile ``dura``) names its
robot in a ``dura`` metadata record and each channel's publisher in the channel's
``caller_id`` metadata.

A file without its summary (a recorder killed, a power cut) is read record by record
up to its last whole chunk (:func:`salvage`); :attr:`Bag.notes` says how much was cut.
"""

from __future__ import annotations

import contextlib
import heapq
import io
import tempfile
from collections.abc import Callable, Iterator, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import IO, Any

from mcap.reader import make_reader
from mcap.records import Channel, Chunk, Footer, Header, Metadata, Schema
from mcap.records import Message as McapMessage
from mcap.stream_reader import StreamReader, breakup_chunk

from executive.bags.bag import DURA_PROFILE, Bag, BagTopic, Route
from executive.bags.message import RecordedMessage, ros_message
from executive.bags.ros_messages import Definition, RosTypes
from executive.bags.rosbag2_bag import reason, uncompressed
from executive.bus.message import Message
from knowledge.errors import BagError

ROS_SCHEMAS = ("ros2msg", "ros2idl")
MAGIC = b"\x89MCAP0\r\n"


@dataclass
class Contents:
    """What one MCAP file holds: from its summary, or read record by record if cut."""

    profile: str = ""
    library: str = ""
    schemas: dict[int, Schema] = field(default_factory=dict)
    channels: dict[int, Channel] = field(default_factory=dict)
    counts: dict[int, int] = field(default_factory=dict)  # messages per channel id
    metadata: list[Metadata] = field(default_factory=list)
    start: int | None = None  # ns: the first message's log time
    end: int | None = None
    salvaged: list[McapMessage] | None = None  # a cut file's messages, by log time
    size: int = 0  # bytes
    whole: int = 0  # bytes up to the end of the last whole record


@dataclass
class _File:
    path: Path
    stream: IO[bytes]
    contents: Contents


@dataclass
class McapBag(Bag):
    """One MCAP file, or the MCAP files of a rosbag2 folder (read as one)."""

    distro: str | None = None
    files: list[_File] = field(default_factory=list)
    channels: dict[str, list[tuple[Channel, Schema | None]]] = field(default_factory=dict)
    unpack: Callable[[bytes], bytes] | None = None  # messages compressed one by one
    temporary: tempfile.TemporaryDirectory[str] | None = None  # decompressed files
    extra_types: Mapping[str, Any] = field(default_factory=dict)
    _types: RosTypes | None = None

    def close(self) -> None:
        for file in self.files:
            file.stream.close()
        self.files.clear()
        if self.temporary is not None:
            self.temporary.cleanup()
            self.temporary = None

    def _ros_types(self) -> RosTypes:
        if self._types is None:
            definitions = {
                schema.name: Definition(schema.name, schema.encoding, schema.data.decode())
                for found in self.channels.values()
                for _, schema in found
                if schema is not None and schema.encoding in ROS_SCHEMAS
            }
            self._types = RosTypes(definitions.values(), self.distro, self.extra_types)
        return self._types

    # --- messages -----------------------------------------------------------------

    def messages(
        self, routes: Mapping[str, Route], start: int | None = None, end: int | None = None
    ) -> Iterator[Message]:
        makers = self._makers(routes)
        topics = sorted(routes)
        if self.keys_are_bus_keys and start is not None:  # who runs when the window opens
            states = [t for t in topics if t.startswith("component/")]
            if states:
                yield from self._read(states, makers, None, start - 1)
        yield from self._read(topics, makers, start, end)

    def _read(
        self,
        topics: list[str],
        makers: dict[tuple[int, int], Callable[[McapMessage], Message]],
        at: int | None,
        until: int | None,
    ) -> Iterator[Message]:
        streams = [
            _numbered(i, _records(file, topics, at, until)) for i, file in enumerate(self.files)
        ]
        merged: Iterator[tuple[int, McapMessage]] = (
            streams[0] if len(streams) == 1 else heapq.merge(*streams, key=_log_time)
        )
        while True:
            try:
                index, record = next(merged)
            except StopIteration:
                return
            except Exception as e:  # a corrupt file fails in the library in many ways
                raise BagError(f"{self.path}: truncated or corrupt ({reason(e)})") from e
            yield makers[index, record.channel_id](record)

    def _makers(
        self, routes: Mapping[str, Route]
    ) -> dict[tuple[int, int], Callable[[McapMessage], Message]]:
        """Return how to make a bus message of each routed channel's records, per file."""
        makers: dict[tuple[int, int], Callable[[McapMessage], Message]] = {}
        for index, file in enumerate(self.files):
            contents = file.contents
            for channel in contents.channels.values():
                route = routes.get(channel.topic)
                if route is not None:
                    schema = contents.schemas.get(channel.schema_id)
                    makers[index, channel.id] = self._maker(channel, schema, route)
        return makers

    def _maker(
        self, channel: Channel, schema: Schema | None, route: Route
    ) -> Callable[[McapMessage], Message]:
        key = route.key
        caller = channel.metadata.get("caller_id") or route.caller
        unpack = self.unpack
        topic = channel.topic
        count = self.counter(topic)
        if channel.message_encoding == "json":

            def plain(record: McapMessage) -> Message:
                sent = record.publish_time or None
                return RecordedMessage.at_ns(
                    key, record.data, caller, sent, record.log_time, on_undecodable=count
                )

            return plain

        def unknown(why: str) -> None:
            self.note(f"{self.path}: topic '{topic}' not decoded: {why}")

        if channel.message_encoding == "cdr":
            decoder = self._ros_types().decoder(schema.name if schema else "", unknown)
        else:
            encoding = channel.message_encoding
            decoder = RosTypes.undecodable(f"its encoding '{encoding}' is not CDR or JSON", unknown)

        def ros(record: McapMessage) -> Message:
            times = (record.publish_time or None, record.log_time)
            return ros_message(
                key, record.data, caller, times, decode=decoder, on_undecodable=count, unpack=unpack
            )

        return ros


def _records(
    file: _File, topics: list[str], at: int | None, until: int | None
) -> Iterator[McapMessage]:
    contents = file.contents
    if contents.salvaged is None:
        file.stream.seek(0)
        reader = make_reader(file.stream)
        for _, _, record in reader.iter_messages(
            topics=topics, starting_at=at, ending_at=until, log_time_order=True
        ):
            yield record
        return
    wanted = {c.id for c in contents.channels.values() if c.topic in topics}
    for record in contents.salvaged:
        if (
            record.channel_id in wanted
            and (at is None or record.log_time >= at)
            and (until is None or record.log_time <= until)
        ):
            yield record


def _numbered(index: int, records: Iterator[McapMessage]) -> Iterator[tuple[int, McapMessage]]:
    """The records of the file ``index`` (bound now: a generator expression would read
    the loop's last index)."""
    for record in records:
        yield index, record


def _log_time(item: tuple[int, McapMessage]) -> int:
    return item[1].log_time


# --- opening ------------------------------------------------------------------------


def open_mcap(
    path: Path,
    files: list[Path],
    distro: str | None = None,
    *,
    compression: str = "",
    extra_types: Mapping[str, Any] | None = None,
) -> McapBag:
    """Open MCAP files as one bag (``path`` names it in messages); a file cut off is
    read up to its last whole chunk, and :attr:`Bag.notes` says how much was cut.

    Args:
        compression: rosbag2's compression mode: ``file``, ``message`` or none.

    Raises:
        BagError: a file is not MCAP, or is corrupt, or holds no whole chunk.
    """
    bag = McapBag(path=path, format="", distro=distro)
    bag.extra_types = extra_types or {}
    try:
        files, bag.temporary, bag.unpack = uncompressed(files, compression)
        for name in files:
            stream = name.open("rb")
            bag.files.append(_File(name, stream, Contents()))
            bag.files[-1].contents = read_contents(name, stream)
        _read_summaries(bag)
    except BagError:
        bag.close()
        raise
    except Exception as e:  # the library fails in many ways on a file that is not MCAP
        bag.close()
        raise BagError(f"{path}: truncated or corrupt MCAP ({reason(e)})") from e
    return bag


def read_contents(path: Path, stream: IO[bytes]) -> Contents:
    """Read what a file holds from its summary; a file without one is salvaged.

    Raises:
        BagError: it is not MCAP, or a cut file holds no whole chunk.
    """
    size = stream.seek(0, io.SEEK_END)
    stream.seek(0)
    if stream.read(len(MAGIC)) != MAGIC:
        raise BagError(f"{path}: truncated or corrupt MCAP (it does not start as MCAP does)")
    stream.seek(-len(MAGIC), io.SEEK_END)
    summary, header, metadata = None, Header("", ""), []
    if stream.read(len(MAGIC)) == MAGIC:
        with contextlib.suppress(Exception):  # a broken summary: read it as cut
            stream.seek(0)
            reader = make_reader(stream)
            header = reader.get_header()
            metadata = list(reader.iter_metadata())
            summary = reader.get_summary()
    if summary is None or summary.statistics is None:
        return salvage(path, stream)
    statistics = summary.statistics
    start = end = None
    if statistics.message_count:  # from the messages: the statistics may say otherwise
        start = next(reader.iter_messages(log_time_order=True))[2].log_time
        end = next(reader.iter_messages(log_time_order=True, reverse=True))[2].log_time
    return Contents(
        profile=header.profile,
        library=header.library,
        schemas=dict(summary.schemas),
        channels=dict(summary.channels),
        counts=dict(statistics.channel_message_counts),
        metadata=metadata,
        start=start,
        end=end,
        size=size,
        whole=size,
    )


def salvage(path: Path, stream: IO[bytes]) -> Contents:
    """Read a file record by record up to its last whole record (a chunk cut in the
    middle, or a missing summary, ends it).

    Raises:
        BagError: not even the header is whole.
    """
    size = stream.seek(0, io.SEEK_END)
    stream.seek(0)
    contents = Contents(salvaged=[], size=size)
    messages: list[McapMessage] = []
    # the cut: a record that does not end, or ends in garbage, ends the reading
    with contextlib.suppress(Exception):
        for record in StreamReader(stream, emit_chunks=True, record_size_limit=size).records:
            inner = (
                breakup_chunk(record, validate_crc=True) if isinstance(record, Chunk) else [record]
            )
            for item in inner:
                if isinstance(item, Header):
                    contents.profile, contents.library = item.profile, item.library
                elif isinstance(item, Schema):
                    contents.schemas[item.id] = item
                elif isinstance(item, Channel):
                    contents.channels[item.id] = item
                elif isinstance(item, McapMessage):
                    messages.append(item)
                elif isinstance(item, Metadata):
                    contents.metadata.append(item)
            if isinstance(record, Footer):
                break
            contents.whole = stream.tell()
    if contents.whole == 0:
        raise BagError(f"{path}: truncated or corrupt MCAP (not even its header is whole)")
    messages.sort(key=lambda m: m.log_time)
    contents.salvaged = messages
    for message in messages:
        contents.counts[message.channel_id] = contents.counts.get(message.channel_id, 0) + 1
    if messages:
        contents.start, contents.end = messages[0].log_time, messages[-1].log_time
    return contents


def _read_summaries(bag: McapBag) -> None:
    counts: dict[str, int] = {}
    callers: dict[str, set[str]] = {}
    starts, ends = [], []
    profiles = set()
    for file in bag.files:
        contents = file.contents
        profiles.add(contents.profile)
        if contents.start is not None and contents.end is not None:
            starts.append(contents.start)
            ends.append(contents.end)
        for channel in contents.channels.values():
            schema = contents.schemas.get(channel.schema_id) if channel.schema_id else None
            bag.channels.setdefault(channel.topic, []).append((channel, schema))
            counts[channel.topic] = counts.get(channel.topic, 0) + contents.counts.get(
                channel.id, 0
            )
            if channel.metadata.get("caller_id"):
                callers.setdefault(channel.topic, set()).add(channel.metadata["caller_id"])
        if contents.profile == DURA_PROFILE:
            for record in contents.metadata:
                if record.name == DURA_PROFILE:
                    bag.robot = record.metadata.get("robot") or bag.robot
        elif bag.distro is None:
            bag.distro = _distro(contents.metadata)
        if contents.salvaged is not None:
            bag.note(_cut(file, contents))
    bag.keys_are_bus_keys = profiles == {DURA_PROFILE}
    bag.format = "dura recording (mcap)" if bag.keys_are_bus_keys else "rosbag2 (mcap)"
    bag.start_ns = min(starts) if starts else 0
    bag.end_ns = max(ends) if ends else 0
    bag.topics = tuple(
        BagTopic(name, _type_name(found), counts.get(name, 0), tuple(sorted(callers.get(name, ()))))
        for name, found in sorted(bag.channels.items())
    )


def _cut(file: _File, contents: Contents) -> str:
    count = len(contents.salvaged or ())
    lost = contents.size - contents.whole
    until = "" if contents.end is None else f" (until {contents.end / 1e9:.3f})"
    return (
        f"{file.path}: cut off (no summary: the recording did not end): read "
        f"{count} messages{until} up to its last whole chunk; "
        + (f"{lost} of its {contents.size} bytes after it are lost" if lost else "nothing after it")
    )


def _type_name(found: list[tuple[Channel, Schema | None]]) -> str:
    names = sorted({schema.name for _, schema in found if schema is not None})
    return " | ".join(names) or "?"


def _distro(metadata: list[Metadata]) -> str | None:
    """Return the ROS distribution rosbag2 wrote in its metadata record, if any."""
    for record in metadata:
        if record.name == "rosbag2":
            found = record.metadata.get("ROS_DISTRO") or record.metadata.get("ros_distro")
            if found:
                return found
    return None
