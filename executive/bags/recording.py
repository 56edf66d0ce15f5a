"""Record a robot's bus traffic to MCAP: component topics, observations, diagnoses,
resources, events and component states, so that a run can be opened in MCAP tools
(Foxglove, ``mcap``) and replayed later (``dura replay``).

A recording is an MCAP file of profile ``dura`` (a ``dura`` metadata record names the
robot). Each bus key is a channel per publisher: its topic is the key (``topic/scan``,
``observations``, ``component/lidar/state``), its messages are the payloads as sent
(JSON, with a JSON schema of dura's payloads, :mod:`executive.bags.schemas`), its
``caller_id`` metadata the publisher, each message's ``log_time`` the time it arrived
and its ``publish_time`` the time it was sent. A ROS 2 message (from the robot's ROS 2
topics, which do not travel on the bus) is recorded as rosbag2 records it: its CDR
bytes, on a channel of encoding ``cdr`` whose schema is the type's ``ros2msg``
definition.

It survives a crash: every ``flush_every`` seconds (one by default) the chunk in
progress is completed and written out, so that a recorder killed at any moment (or a
machine that loses power, once the system wrote its buffers) leaves a file that
``dura replay`` reads up to its last whole chunk: at most the last second is lost.
``dura record --repair FILE`` rewrites such a file whole (:func:`repair`).

It is bounded: when the file reaches ``max_size`` bytes it is closed and renamed
``OUT.1.mcap`` (older ones move up to ``OUT.<keep>.mcap``; the oldest goes) and a new
``OUT.mcap`` begins, with the latest state of every component first, so that each
file replays on its own. A file that exists when recording starts is rotated too.
"""

from __future__ import annotations

import contextlib
import logging
import threading
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import IO, Any, Protocol

from mcap.writer import CompressionType
from mcap.writer import Writer as McapWriter

from executive.bags.bag import DURA_PROFILE
from executive.bags.mcap_bag import read_contents
from executive.bags.schemas import schema_bytes, schema_name
from executive.bus.keys import DIAGNOSES, EVENTS, OBSERVATIONS, RESOURCES, component
from executive.bus.message import Message, encode
from executive.bus.service import Context, Service
from executive.bus.session import Bus
from executive.bus.topic_source import TopicSource
from executive.ros2.message import RosMessage
from knowledge.errors import BagError, DuraError

log = logging.getLogger("dura.record")

MB = 1 << 20
DEFAULT_MAX_SIZE = 100 * MB
DEFAULT_KEEP = 3
DEFAULT_FLUSH_EVERY = 1.0  # seconds between two complete chunks on disk
RECORDED = ("topic/**", OBSERVATIONS, DIAGNOSES, RESOURCES, EVENTS, component("*", "state"))
SNAPSHOT_CALLER = "executive"  # who publishes component states


def rotated(path: Path, number: int) -> Path:
    """Return the ``number``-th older file of a recording: ``OUT.1.mcap``."""
    return path.with_name(f"{path.stem}.{number}{path.suffix}")


class Recorder:
    """Writes bus messages of one robot to an MCAP file, rotated by size; thread-safe.

    Args:
        path: the file (``OUT.mcap``); older files go beside it.
        robot: the robot's name (in the file's metadata).
        max_size: bytes after which the file is rotated.
        keep: how many older files to keep.
        flush_every: seconds after which what was recorded is on disk as a whole chunk.
        ros2_definition: the ``ros2msg`` text of a ROS 2 type: ROS 2 messages (that
            know their type) are then recorded as CDR with that schema, as rosbag2 does.

    Raises:
        BagError: the file cannot be written.
    """

    def __init__(
        self,
        path: Path,
        robot: str,
        *,
        max_size: int = DEFAULT_MAX_SIZE,
        keep: int = DEFAULT_KEEP,
        library: str = "dura",
        flush_every: float = DEFAULT_FLUSH_EVERY,
        ros2_definition: Callable[[str], str] | None = None,
    ) -> None:
        self.path = Path(path)
        self.robot = robot
        self.max_size = max_size
        self.keep = keep
        self.library = library
        self.messages = 0  # written, in all files
        self.flushed = 0  # of them, on disk in whole chunks (handed to the system)
        self.failure: BagError | None = None  # why the flusher stopped the recording
        self.files = 0  # begun
        self._lock = threading.Lock()
        self._states: dict[str, Message] = {}  # the newest state of each component
        self._file: IO[bytes] | None = None
        self._writer: McapWriter | None = None
        self._schemas: dict[str, int] = {}
        self._channels: dict[tuple[str, str, str], int] = {}
        self._sequence: dict[int, int] = {}
        self._last = 0  # the newest message's arrival (ns): when the next file begins
        self.flush_every = flush_every
        self.ros2_definition = ros2_definition
        self._unflushed = False  # written since the last flush
        self._closed = threading.Event()
        with self._lock:
            if self.path.exists():
                self._shift()
            self._begin()
        self._flusher = threading.Thread(target=self._flush_loop, name="dura-record-flush")
        self._flusher.daemon = True
        self._flusher.start()

    # --- writing --------------------------------------------------------------------

    def write(self, message: Message) -> bool:
        """Record a message (keys dura does not record are ignored); whether it did.

        Raises:
            BagError: the file cannot be written (the recorder is closed then).
        """
        schema = schema_name(message.key)
        if schema is None:
            return False
        with self._lock:
            writer = self._writer
            if writer is None:
                return False
            try:
                self._add(writer, message, schema, self._ros_type(message))
                self._unflushed = True
                if message.key.startswith("component/"):
                    self._states[message.key] = message
                if self._file is not None and self._file.tell() >= self.max_size:
                    self._rotate()
            except OSError as e:
                self._abandon()
                raise BagError(
                    f"{self.path}: cannot write the recording ({e.strerror or e})"
                ) from e
        return True

    def has_state(self, key: str) -> bool:
        """Tell whether a state of that key was recorded."""
        with self._lock:
            return key in self._states

    def close(self) -> None:
        """Finish the file (idempotent)."""
        self._closed.set()
        with self._lock:
            self._finish()
        if self._flusher is not threading.current_thread():
            self._flusher.join()

    def flush(self) -> None:
        """Write what was recorded as a whole chunk and hand it to the system.

        Raises:
            BagError: the file cannot be written (the recorder is closed then).
        """
        with self._lock:
            writer, file = self._writer, self._file
            if writer is None or file is None or not self._unflushed:
                return
            try:
                writer.flush()  # type: ignore[no-untyped-call]
                self._unflushed = False
                self.flushed = self.messages
            except OSError as e:
                self._abandon()
                raise BagError(
                    f"{self.path}: cannot write the recording ({e.strerror or e})"
                ) from e

    def _flush_loop(self) -> None:
        while not self._closed.wait(self.flush_every):
            try:
                self.flush()
            except BagError as e:
                self.failure = e
                log.error("recording stopped: %s", e)
                return

    def __enter__(self) -> Recorder:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    # --- the file -------------------------------------------------------------------

    def _ros_type(self, message: Message) -> str:
        """The ROS 2 type a message is recorded as (CDR), or "" (its JSON)."""
        if self.ros2_definition is None or not isinstance(message, RosMessage):
            return ""
        return message.type

    def _add(self, writer: McapWriter, message: Message, schema: str, ros_type: str = "") -> None:
        channel = self._channel(writer, message.key, message.caller_id, schema, ros_type)
        received = message.received_ns
        sent = message.sent_ns
        sequence = self._sequence[channel] = self._sequence.get(channel, 0) + 1
        writer.add_message(channel, received, message.raw, received if sent is None else sent,
                           sequence)  # fmt: skip
        self.messages += 1
        self._last = max(self._last, received)

    def _channel(
        self, writer: McapWriter, key: str, caller: str, schema: str, ros_type: str
    ) -> int:
        found = self._channels.get((key, caller, ros_type))
        if found is None:
            schema_id = self._schemas.get(ros_type or schema)
            if schema_id is None:
                schema_id = self._schema(writer, schema, ros_type)
                self._schemas[ros_type or schema] = schema_id
            metadata = {"caller_id": caller} if caller else {}
            encoding = "cdr" if ros_type else "json"
            found = writer.register_channel(key, encoding, schema_id, metadata)
            self._channels[key, caller, ros_type] = found
        return found

    def _schema(self, writer: McapWriter, schema: str, ros_type: str) -> int:
        definition = self.ros2_definition
        if not ros_type or definition is None:
            return int(writer.register_schema(schema, "jsonschema", schema_bytes(schema)))
        try:
            text = definition(ros_type)
        except Exception as e:  # a type the library cannot write out: CDR without schema
            log.warning("recording %s without its definition: %s", ros_type, e)
            return 0
        return int(writer.register_schema(ros_type, "ros2msg", text.encode()))

    def _begin(self) -> None:
        try:
            self._file = self.path.open("wb")
        except OSError as e:
            raise BagError(f"{self.path}: cannot write the recording ({e.strerror or e})") from e
        chunk = max(4096, min(MB, self.max_size // 8))
        writer = McapWriter(self._file, chunk_size=chunk, compression=CompressionType.ZSTD)
        writer.start(profile=DURA_PROFILE, library=self.library)
        writer.add_metadata(DURA_PROFILE, {"robot": self.robot, "format": "1"})
        self._writer = writer
        self._unflushed = True  # the header and metadata, on disk within a second
        self._schemas, self._channels, self._sequence = {}, {}, {}
        self.files += 1
        for state in self._states.values():  # each file replays on its own
            snapshot = Message.at_ns(
                state.key, state.raw, state.caller_id, state.sent_ns, self._last
            )
            self._add(writer, snapshot, "dura.ComponentState")

    def _finish(self) -> None:
        writer, file = self._writer, self._file
        self._writer, self._file = None, None
        if writer is not None:
            writer.finish()  # type: ignore[no-untyped-call]
        if file is not None:
            file.close()
        self.flushed = self.messages

    def _abandon(self) -> None:
        """Close after a failure without finishing (the file is cut off)."""
        file = self._file
        self._writer, self._file = None, None
        if file is not None:
            with contextlib.suppress(OSError):
                file.close()

    def _rotate(self) -> None:
        self._finish()
        self._shift()
        self._begin()

    def _shift(self) -> None:
        """Move ``OUT.mcap`` to ``OUT.1.mcap``, and each older file one further."""
        if self.keep == 0:
            self.path.unlink(missing_ok=True)
            return
        rotated(self.path, self.keep).unlink(missing_ok=True)
        for number in range(self.keep - 1, 0, -1):
            older = rotated(self.path, number)
            if older.exists():
                older.rename(rotated(self.path, number + 1))
        self.path.rename(rotated(self.path, 1))


@dataclass(frozen=True)
class Repaired:
    """What :func:`repair` kept of a file: its messages up to its last whole chunk."""

    messages: int
    kept: int  # bytes of the cut file that were read
    lost: int  # bytes after its last whole chunk
    end: float | None  # seconds: the last message kept
    rewritten: bool  # it was cut off (else whole: left as it was)


def repair(path: Path) -> Repaired:
    """Rewrite an MCAP file cut off (a recorder killed) as a whole one, with its
    messages up to its last whole chunk; a whole file is left as it is.

    Raises:
        BagError: it is not MCAP, or not even its header is whole, or it cannot be
            written.
    """
    path = Path(path)
    try:
        with path.open("rb") as stream:
            contents = read_contents(path, stream)
    except OSError as e:
        raise BagError(f"{path}: cannot read it ({e.strerror or e})") from e
    found = contents.salvaged
    end = None if contents.end is None else contents.end / 1e9
    if found is None:
        return Repaired(sum(contents.counts.values()), contents.size, 0, end, rewritten=False)
    part = path.with_name(path.name + ".repairing")
    try:
        with part.open("wb") as out:
            writer = McapWriter(out, compression=CompressionType.ZSTD)
            writer.start(profile=contents.profile, library=contents.library)
            for record in contents.metadata:
                writer.add_metadata(record.name, record.metadata)
            schemas = {
                s.id: writer.register_schema(s.name, s.encoding, s.data)
                for s in contents.schemas.values()
            }
            channels = {
                c.id: writer.register_channel(
                    c.topic, c.message_encoding, schemas.get(c.schema_id, 0), c.metadata
                )
                for c in contents.channels.values()
            }
            for m in found:
                if m.channel_id in channels:
                    writer.add_message(channels[m.channel_id], m.log_time, m.data, m.publish_time,
                                       m.sequence)  # fmt: skip
            writer.finish()  # type: ignore[no-untyped-call]
        part.replace(path)
    except OSError as e:
        part.unlink(missing_ok=True)
        raise BagError(f"{path}: cannot write the repaired file ({e.strerror or e})") from e
    return Repaired(len(found), contents.whole, contents.size - contents.whole, end, rewritten=True)


class RecordedTopics(TopicSource, Protocol):
    """Topics whose messages do not travel on the bus, recorded in their own types: a
    robot's ROS 2 topics (:class:`~executive.ros2.topics.Ros2Topics`), as CDR with
    their type's ``ros2msg`` definition."""

    @property
    def keys(self) -> list[str]:
        """The keys of the topics (``topic/scan``)."""

    def definition(self, type: str) -> str:
        """Return the ``ros2msg`` definition of a type (``sensor_msgs/msg/LaserScan``)."""


class BusRecording:
    """A recorder fed by a bus session: it subscribes to every recorded key.

    Args:
        bus: the robot's bus.
        recorder: where messages go.
        on_failure: called once if writing fails (e.g. the disk is full).
        ros2: the robot's ROS 2 topics (not on the bus), recorded too.
    """

    def __init__(
        self,
        bus: Bus,
        recorder: Recorder,
        on_failure: Callable[[BagError], None] | None = None,
        ros2: RecordedTopics | None = None,
    ) -> None:
        self.bus = bus
        self.recorder = recorder
        self.ros2 = ros2
        self.failure: BagError | None = None
        self._on_failure = on_failure
        self._entities: list[Any] = []

    @classmethod
    def to_file(
        cls,
        bus: Bus,
        path: Path,
        *,
        max_size: int = DEFAULT_MAX_SIZE,
        keep: int = DEFAULT_KEEP,
        flush_every: float = DEFAULT_FLUSH_EVERY,
        ros2: RecordedTopics | None = None,
        on_failure: Callable[[BagError], None] | None = None,
    ) -> BusRecording:
        """A recording of a robot's bus and ROS 2 topics to a file (``dura record``'s and
        ``dura run --record``'s): see :class:`Recorder`.

        Raises:
            BagError: the file cannot be written.
        """
        definition = None if ros2 is None else ros2.definition
        recorder = Recorder(
            path,
            bus.robot,
            max_size=max_size,
            keep=keep,
            flush_every=flush_every,
            ros2_definition=definition,
        )
        return cls(bus, recorder, on_failure, ros2)

    def start(self, states: Sequence[Mapping[str, Any]] = ()) -> None:
        """Subscribe; then record ``states`` (component state payloads: who runs now)
        for the components no state was recorded of meanwhile."""
        for key in RECORDED:
            self._entities.append(self.bus.subscribe(key, self._on_message, decoded=False))
        if self.ros2 is not None:
            for key in self.ros2.keys:
                try:
                    self._entities.append(self.ros2.subscribe(key, self._on_message))
                except DuraError as e:  # e.g. DDS refused the reader: the rest is recorded
                    log.warning("%s is not recorded: %s", key, e)
        for state in states:
            key = component(str(state["component"]), "state")
            if not self.recorder.has_state(key):
                raw = encode(state)
                self._on_message(Message.at_ns(key, raw, SNAPSHOT_CALLER, None, time.time_ns()))

    def stop(self) -> None:
        for entity in self._entities:
            with contextlib.suppress(Exception):  # already gone with the bus
                entity.undeclare()
        self._entities = []
        self.recorder.close()

    def _on_message(self, message: Message) -> None:
        try:
            self.recorder.write(message)
        except BagError as e:
            if self.failure is None:
                self.failure = e
                log.error("recording stopped: %s", e)
                if self._on_failure is not None:
                    self._on_failure(e)


class Recording(Service):
    """The executive's own recording (``dura run --record``): it records from its
    configuration on, before the other services are configured, so it sees every
    component state from the first; and the robot's ROS 2 topics (``ros2``), as CDR
    with their ``ros2msg`` schemas."""

    name = "recording"

    def __init__(
        self,
        context: Context,
        path: Path,
        *,
        max_size: int = DEFAULT_MAX_SIZE,
        flush_every: float = DEFAULT_FLUSH_EVERY,
        ros2: RecordedTopics | None = None,
    ) -> None:
        super().__init__(context)
        self.path = path
        self.max_size = max_size
        self.flush_every = flush_every
        self.ros2 = ros2
        self._recording: BusRecording | None = None

    @property
    def messages(self) -> int:
        """How many messages it recorded so far."""
        return self._recording.recorder.messages if self._recording is not None else 0

    def on_configure(self) -> None:
        self._recording = BusRecording.to_file(
            self.context.bus,
            self.path,
            max_size=self.max_size,
            flush_every=self.flush_every,
            ros2=self.ros2,
        )
        self._recording.start()

    def on_shutdown(self) -> None:
        if self._recording is not None:
            self._recording.stop()
            self._recording = None
