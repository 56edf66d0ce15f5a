"""A dura recording's ROS 2 topics as a rosbag2 bag: what ``rosbags`` (its rosbag2
reader and ``AnyReader``), ``ros2 bag`` and Foxglove open as a ROS 2 bag.

A dura recording cannot itself be a rosbag2 file: the MCAP ``ros2`` profile (which
rosbags' reader requires, and rosbag2 writes) says that every channel is CDR with a
``ros2msg`` or ``ros2idl`` schema, and a recording also holds dura's own messages
(observations, diagnoses, events, component states) as JSON with JSON schemas; rosbags
refuses a file of another profile, and cannot read a JSON schema. So
:func:`export_ros2` writes the recording's ROS 2 channels (CDR, ``ros2msg``) as a
rosbag2 folder of their own (``metadata.yaml`` and one MCAP file of profile ``ros2``),
one topic per ROS 2 topic whatever its publishers, the messages with their recorded
receive times; dura's JSON channels stay in the recording.
"""

from __future__ import annotations

import contextlib
import shutil
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import IO, Any

from mcap.reader import make_reader
from mcap.records import Message as McapMessage
from rosbags.rosbag2 import StoragePlugin, Writer
from rosbags.typesys import Stores, get_types_from_msg, get_typestore

from executive.bags.bag import DURA_PROFILE
from executive.bags.mcap_bag import Contents, read_contents
from knowledge.errors import BagError


@dataclass(frozen=True)
class Exported:
    """What :func:`export_ros2` wrote: its ROS 2 topics and messages, and the
    channels left in the recording (dura's JSON ones, ROS 2 ones without a schema)."""

    topics: tuple[str, ...]
    messages: int
    left: tuple[str, ...]


def export_ros2(path: Path, out: Path) -> Exported:
    """Write the ROS 2 topics of a dura recording (whole, or cut off: up to its last
    whole chunk) as a rosbag2 bag in the new folder ``out``.

    Raises:
        BagError: it is not a dura recording, ``out`` exists, or it cannot be written.
    """
    if out.exists():
        raise BagError(f"{out}: exists already (the bag is written to a new folder)")
    try:
        with path.open("rb") as stream:
            contents = read_contents(path, stream)
            if contents.profile != DURA_PROFILE:
                raise BagError(f"{path}: not a dura recording (its profile is "
                               f"'{contents.profile}'; a ROS 2 bag is one already)")  # fmt: skip
            return _write_bag(contents, _messages(contents, stream), out)
    except OSError as e:
        shutil.rmtree(out, ignore_errors=True)
        raise BagError(f"{e.filename or path}: cannot export ({e.strerror or e})") from e


def _messages(contents: Contents, stream: IO[bytes]) -> Iterator[McapMessage]:
    if contents.salvaged is not None:
        yield from contents.salvaged
        return
    stream.seek(0)
    for _, _, message in make_reader(stream).iter_messages(log_time_order=True):
        yield message


def _write_bag(contents: Contents, messages: Iterator[McapMessage], out: Path) -> Exported:
    topics: dict[tuple[str, str], Any] = {}  # (ROS 2 topic, type) -> its connection
    by_channel: dict[int, Any] = {}
    left: set[str] = set()
    written = 0
    writer = Writer(out, version=Writer.VERSION_LATEST, storage_plugin=StoragePlugin.MCAP)
    try:
        with writer:
            for channel in contents.channels.values():
                schema = contents.schemas.get(channel.schema_id)
                ros = schema is not None and schema.encoding == "ros2msg"
                if channel.message_encoding != "cdr" or schema is None or not ros:
                    left.add(channel.topic)
                    continue
                name = "/" + channel.topic.removeprefix("topic/")  # a ROS 2 topic's bus key
                found = topics.get((name, schema.name))
                if found is None:
                    text = schema.data.decode()
                    found = writer.add_connection(
                        name, schema.name, msgdef=text, rihs01=_rihs01(schema.name, text)
                    )
                    topics[name, schema.name] = found
                by_channel[channel.id] = found
            for message in messages:
                connection = by_channel.get(message.channel_id)
                if connection is not None:
                    writer.write(connection, message.log_time, message.data)
                    written += 1
    except BagError:
        shutil.rmtree(out, ignore_errors=True)
        raise
    except Exception as e:  # rosbags: a definition it cannot read, a write that failed
        with contextlib.suppress(OSError):
            shutil.rmtree(out)
        raise BagError(f"{out}: cannot write the ROS 2 bag ({e})") from e
    return Exported(tuple(sorted(n for n, _ in topics)), written, tuple(sorted(left)))


def _rihs01(name: str, text: str) -> str:
    """The type's hash (REP 2011), from the definition the recording holds."""
    try:
        store = get_typestore(Stores.EMPTY)
        store.register(get_types_from_msg(text, name))
        found: str = store.hash_rihs01(name)
    except Exception as e:  # rosbags fails in many ways on a definition it cannot read
        raise BagError(f"type {name}: its definition in the recording is unreadable ({e})") from e
    return found
