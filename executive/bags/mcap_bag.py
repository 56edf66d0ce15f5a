"""MCAP files read with the ``mcap`` library: rosbag2's MCAP storage and dura's own
recordings.

A channel's messages are CDR (ROS 2, typed by the channel's schema: its ``ros2msg`` or
``ros2idl`` definition, else ``rosbags``' type store) or JSON (dura's recordings). The
receive time is the message's ``log_time``; its ``publish_time`` is the send time
(ROS 2 Jazzy and later record the publisher's; older bags repeat the receive time).
A dura recording (profile ``dura``) names its robot in a ``dura`` metadata record and
each channel's publisher in the channel's ``caller_id`` metadata.
"""

from __future__ import annotations

import contextlib
import heapq
import io
from collections.abc import Callable, Iterator, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import IO

from mcap.reader import McapReader, make_reader
from mcap.records import Channel, Schema
from mcap.records import Message as McapMessage

from executive.bags.bag import DURA_PROFILE, Bag, BagTopic, Route
from executive.bags.ros_messages import Definition, RosTypes
from executive.bus.session import Message
from executive.ros2.message import RosMessage
from knowledge.errors import BagError

ROS_SCHEMAS = ("ros2msg", "ros2idl")
MAGIC = b"\x89MCAP0\r\n"
Record = tuple[Schema | None, Channel, McapMessage]


@dataclass
class _File:
    path: Path
    stream: IO[bytes]
    reader: McapReader


@dataclass
class McapBag(Bag):
    """One MCAP file, or the MCAP files of a rosbag2 folder (read as one)."""

    distro: str | None = None
    files: list[_File] = field(default_factory=list)
    channels: dict[str, list[tuple[Channel, Schema | None]]] = field(default_factory=dict)
    _types: RosTypes | None = None

    def close(self) -> None:
        for file in self.files:
            file.stream.close()
        self.files.clear()

    # --- types --------------------------------------------------------------------

    def _ros_types(self) -> RosTypes:
        if self._types is None:
            definitions = {
                schema.name: Definition(schema.name, schema.encoding, schema.data.decode())
                for found in self.channels.values()
                for _, schema in found
                if schema is not None and schema.encoding in ROS_SCHEMAS and schema.data
            }
            self._types = RosTypes(definitions.values(), self.distro, str(self.path))
        return self._types

    def check(self, routes: Mapping[str, Route]) -> None:
        for name in routes:
            for channel, schema in self.channels.get(name, []):
                encoding = channel.message_encoding
                if encoding == "json":
                    continue
                if encoding != "cdr":
                    raise BagError(
                        f"{self.path}: topic '{name}' has messages in '{encoding}', which "
                        "dura cannot read (it reads ROS 2 CDR and JSON)"
                    )
                msgtype = schema.name if schema is not None else ""
                if not msgtype or not self._ros_types().knows(msgtype):
                    store = self._ros_types().store.name.lower()
                    raise BagError(
                        f"{self.path}: unknown message type '{msgtype or '?'}' of topic "
                        f"'{name}' (the bag does not define it and rosbags' {store} types "
                        "do not know it)"
                    )

    # --- messages -----------------------------------------------------------------

    def messages(
        self, routes: Mapping[str, Route], start: float | None = None, end: float | None = None
    ) -> Iterator[Message]:
        self.check(routes)
        makers = self._makers(routes)
        topics = sorted(routes)
        at = None if start is None else round(start * 1e9)
        until = None if end is None else round(end * 1e9)
        if self.keys_are_bus_keys and at is not None:  # who runs when the window opens
            states = [t for t in topics if t.startswith("component/")]
            if states:
                yield from self._read(states, makers, None, at - 1)
        yield from self._read(topics, makers, at, until)

    def _read(
        self,
        topics: list[str],
        makers: dict[tuple[int, int], Callable[[McapMessage], Message]],
        at: int | None,
        until: int | None,
    ) -> Iterator[Message]:
        streams = [
            ((i, record) for record in file.reader.iter_messages(
                topics=topics, starting_at=at, ending_at=until, log_time_order=True))
            for i, file in enumerate(self.files)
        ]  # fmt: skip
        merged: Iterator[tuple[int, Record]] = (
            streams[0] if len(streams) == 1 else heapq.merge(*streams, key=_log_time)
        )
        while True:
            try:
                index, (_, channel, record) = next(merged)
            except StopIteration:
                return
            except Exception as e:  # a cut or corrupt file fails in the library in many ways
                raise BagError(f"{self.path}: truncated or corrupt ({_reason(e)})") from e
            yield makers[index, channel.id](record)

    def _makers(
        self, routes: Mapping[str, Route]
    ) -> dict[tuple[int, int], Callable[[McapMessage], Message]]:
        """Return how to make a bus message of each routed channel's records, per file."""
        makers: dict[tuple[int, int], Callable[[McapMessage], Message]] = {}
        for index, file in enumerate(self.files):
            summary = file.reader.get_summary()
            channels = summary.channels if summary is not None else {}
            for channel in channels.values():
                route = routes.get(channel.topic)
                if route is not None:
                    makers[index, channel.id] = self._maker(
                        channel, summary_schema(file, channel), route
                    )
        return makers

    def _maker(
        self, channel: Channel, schema: Schema | None, route: Route
    ) -> Callable[[McapMessage], Message]:
        key = route.key
        caller = channel.metadata.get("caller_id") or route.caller
        if channel.message_encoding == "cdr" and schema is not None:
            decoder = self._ros_types().decoder(schema.name)

            def ros(record: McapMessage) -> Message:
                sent = record.publish_time / 1e9 if record.publish_time else None
                return RosMessage(key, record.data, caller, sent, record.log_time / 1e9,
                                  decode=decoder)  # fmt: skip

            return ros

        def plain(record: McapMessage) -> Message:
            sent = record.publish_time / 1e9 if record.publish_time else None
            return Message(key, record.data, caller, sent, record.log_time / 1e9)

        return plain


def summary_schema(file: _File, channel: Channel) -> Schema | None:
    summary = file.reader.get_summary()
    if summary is None or channel.schema_id == 0:
        return None
    return summary.schemas.get(channel.schema_id)


def _log_time(item: tuple[int, Record]) -> int:
    return item[1][2].log_time


def _reason(error: BaseException) -> str:
    text = str(error).strip()
    return f"{type(error).__name__}: {text}" if text else type(error).__name__


def open_mcap(path: Path, files: list[Path], distro: str | None = None) -> McapBag:
    """Open MCAP files as one bag (``path`` names it in messages).

    Raises:
        BagError: a file is not MCAP, or is truncated or corrupt.
    """
    bag = McapBag(path=path, format="", start=0.0, end=0.0, distro=distro)
    try:
        for name in files:
            stream = name.open("rb")
            bag.files.append(_File(name, stream, make_reader(stream)))
            stream.seek(-len(MAGIC), io.SEEK_END)
            if stream.read(len(MAGIC)) != MAGIC:
                raise BagError(
                    f"{name}: truncated or corrupt MCAP (it does not end as MCAP does: was "
                    "the recording cut off? 'mcap recover' can repair it)"
                )
        _read_summaries(bag)
    except BagError:
        bag.close()
        raise
    except Exception as e:  # the library fails in many ways on a file that is not MCAP
        bag.close()
        raise BagError(f"{path}: truncated or corrupt MCAP ({_reason(e)})") from e
    return bag


def _read_summaries(bag: McapBag) -> None:
    counts: dict[str, int] = {}
    callers: dict[str, set[str]] = {}
    starts, ends = [], []
    profiles = set()
    for file in bag.files:
        profiles.add(file.reader.get_header().profile)
        summary = file.reader.get_summary()
        if summary is None or summary.statistics is None:
            raise BagError(
                f"{file.path}: truncated or corrupt MCAP (no summary: was the recording cut "
                "off? 'mcap recover' can repair it)"
            )
        statistics = summary.statistics
        if statistics.message_count:
            starts.append(statistics.message_start_time)
            ends.append(statistics.message_end_time)
        for channel in summary.channels.values():
            schema = summary.schemas.get(channel.schema_id) if channel.schema_id else None
            bag.channels.setdefault(channel.topic, []).append((channel, schema))
            counts[channel.topic] = counts.get(channel.topic, 0) + (
                statistics.channel_message_counts.get(channel.id, 0)
            )
            if channel.metadata.get("caller_id"):
                callers.setdefault(channel.topic, set()).add(channel.metadata["caller_id"])
        if file.reader.get_header().profile == DURA_PROFILE:
            for record in file.reader.iter_metadata():
                if record.name == DURA_PROFILE:
                    bag.robot = record.metadata.get("robot") or bag.robot
        elif bag.distro is None:
            bag.distro = _distro(file.reader)
    bag.keys_are_bus_keys = profiles == {DURA_PROFILE}
    bag.format = "dura recording (mcap)" if bag.keys_are_bus_keys else "rosbag2 (mcap)"
    bag.start = min(starts) / 1e9 if starts else 0.0
    bag.end = max(ends) / 1e9 if ends else 0.0
    bag.topics = tuple(
        BagTopic(name, _type_name(found), counts.get(name, 0), tuple(sorted(callers.get(name, ()))))
        for name, found in sorted(bag.channels.items())
    )


def _type_name(found: list[tuple[Channel, Schema | None]]) -> str:
    names = sorted({schema.name for _, schema in found if schema is not None})
    return " | ".join(names) or "?"


def _distro(reader: McapReader) -> str | None:
    """Return the ROS distribution rosbag2 wrote in its metadata record, if any."""
    with contextlib.suppress(Exception):  # optional: an odd record only loses the hint
        for record in reader.iter_metadata():
            if record.name == "rosbag2":
                found = record.metadata.get("ROS_DISTRO") or record.metadata.get("ros_distro")
                if found:
                    return found
    return None
