"""One Cyclone DDS participant in a robot's ROS 2 domain, and the thread that receives for it.

This module is the one adapter of Cyclone DDS: every DDS entity dura creates is made,
read and deleted here. The participant announces itself as ROS 2 participants do
(user data ``enclave=/;``) and follows the ``CYCLONEDDS_URI`` configuration, as every
ROS 2 process on the robot does.

Reception: one thread waits on a waitset for the read conditions of all readers and
takes what arrived, in batches, as raw CDR bytes with their sample infos (decoding is
left to whoever needs the values: observers of arrivals never pay for it). Readers
marked ``first`` (discovery) are served before the others of the same wake-up, so a
writer is always known before its samples are delivered. Callbacks run on that thread
and must only queue or update their own state.

:meth:`Participant.close` stops the thread and deletes the participant with
everything in it; nothing is left to the garbage collector.
"""

from __future__ import annotations

import ctypes as ct
import itertools
import logging
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from cyclonedds.builtin import (
    BuiltinDataReader,
    BuiltinTopicDcpsParticipant,
    BuiltinTopicDcpsPublication,
    BuiltinTopicDcpsSubscription,
)
from cyclonedds.core import DDSException, Entity, InstanceState, Policy, Qos, SampleState, ViewState
from cyclonedds.domain import DomainParticipant
from cyclonedds.idl import IdlStruct
from cyclonedds.internal import DDS
from cyclonedds.pub import DataWriter
from cyclonedds.sub import DataReader
from cyclonedds.topic import Topic
from cyclonedds.util import duration

# take() without deserialising: DataReader.take would build Python objects of every
# sample, the cost this module exists to avoid
from cyclonedds._clayer import ddspy_take, ddspy_write  # isort: skip

from knowledge.errors import BusError

log = logging.getLogger("dura.ros2")

OnSamples = Callable[[list[Any], float], None]  # (samples, wall time of their take)
_ANY = SampleState.Any | ViewState.Any | InstanceState.Any
_BATCH = 256
_BUILTIN = {
    "participant": BuiltinTopicDcpsParticipant,
    "publication": BuiltinTopicDcpsPublication,
    "subscription": BuiltinTopicDcpsSubscription,
}


@dataclass(frozen=True)
class Announcement:
    """A participant, reader or writer that DDS discovery found (alive) or lost."""

    guid: bytes
    alive: bool
    handle: int  # its instance handle; a writer's is the publication handle of its samples
    participant: bytes = b""  # of a reader or writer
    topic: str = ""  # DDS topic of a reader or writer, e.g. rt/scan
    type: str = ""  # DDS type name, e.g. sensor_msgs::msg::dds_::LaserScan_


def _announcement(sample: Any) -> Announcement:
    info = sample.sample_info
    participant = getattr(sample, "participant_key", None)
    return Announcement(
        sample.key.bytes,
        info.instance_state == InstanceState.Alive,
        int(info.instance_handle),
        participant.bytes if participant is not None else b"",
        str(getattr(sample, "topic_name", None) or ""),
        str(getattr(sample, "type_name", None) or ""),
    )


class _Waitsets:
    """The few C calls of Cyclone that the binding lacks in the form needed here.

    A waitset must say *which* conditions fired. The library handle is our own, so
    that our prototypes never change the binding's.
    """

    def __init__(self) -> None:
        lib = ct.CDLL(DDS._dll_handle._name)  # the binding's own library
        entity, attach = ct.c_int32, ct.c_ssize_t
        self.create_waitset = _proto(lib.dds_create_waitset, entity, entity)
        self.create_guard = _proto(lib.dds_create_guardcondition, entity, entity)
        self.set_guard = _proto(lib.dds_set_guardcondition, ct.c_int32, entity, ct.c_bool)
        self.create_readcondition = _proto(
            lib.dds_create_readcondition, entity, entity, ct.c_uint32
        )
        self.attach = _proto(lib.dds_waitset_attach, ct.c_int32, entity, entity, attach)
        self.wait = _proto(
            lib.dds_waitset_wait, ct.c_int32, entity, ct.POINTER(attach), ct.c_size_t, ct.c_int64
        )
        self.delete = _proto(lib.dds_delete, ct.c_int32, entity)
        self.lookup_participant = _proto(
            lib.dds_lookup_participant, ct.c_int32, ct.c_uint32, ct.POINTER(entity), ct.c_size_t
        )


def _proto(function: Any, result: Any, *arguments: Any) -> Any:
    function.restype = result
    function.argtypes = list(arguments)
    return function


_C = _Waitsets()


def participants_in(domain_id: int) -> int:
    """Count the participants this process has in a domain (tests: none may be left)."""
    return max(0, int(_C.lookup_participant(domain_id, None, 0)))


class Reader:
    """A DDS reader whose samples go to a callback on the participant's receive thread."""

    def __init__(self, participant: Participant, entity: DataReader[Any], topic: str) -> None:
        self.topic = topic
        self.entity = entity
        self._participant = participant

    @property
    def handle(self) -> int:
        return int(self.entity._ref)

    @property
    def guid(self) -> bytes:
        return bytes(self.entity.guid.bytes)

    def matched(self) -> int:
        """Count the writers this reader is matched with (0 once deleted)."""
        try:
            return len(self.entity.get_matched_publications())
        except DDSException:
            return 0

    def close(self) -> None:
        """Delete the reader (idempotent)."""
        self._participant._delete(self)


class Writer:
    """A DDS writer of one ROS 2 message type."""

    def __init__(self, participant: Participant, entity: DataWriter[Any], topic: str) -> None:
        self.topic = topic
        self.entity = entity
        self._participant = participant

    @property
    def guid(self) -> bytes:
        return bytes(self.entity.guid.bytes)

    @property
    def instance_handle(self) -> int:
        """Return the writer's instance handle, which its readers see as the publication handle."""
        return int(self.entity.instance_handle) & 0xFFFF_FFFF_FFFF_FFFF  # the binding may sign it

    def matched(self) -> int:
        """Count the readers this writer is matched with (0 once deleted)."""
        try:
            return len(self.entity.get_matched_subscriptions())
        except DDSException:
            return 0

    def write_raw(self, data: bytes) -> None:
        """Publish a sample already serialised (XCDR1, with its encapsulation header).

        Raises:
            BusError: DDS refused it.
        """
        if ddspy_write(self.entity._ref, data) < 0:
            raise BusError(f"cannot write on DDS topic '{self.topic}'")

    def write(self, sample: IdlStruct) -> None:
        """Publish a sample (serialised by Cyclone, XCDR1).

        Raises:
            BusError: DDS refused it (e.g. the participant is closed).
        """
        try:
            self.entity.write(sample)
        except DDSException as e:
            raise BusError(f"cannot write on DDS topic '{self.topic}': {e}") from e

    def close(self) -> None:
        self._participant._delete(self)


class Participant:
    """A DDS domain participant that receives on a thread of its own.

    Raises:
        BusError: Cyclone DDS cannot create the participant (its configuration).
    """

    def __init__(self, domain_id: int, *, name: str = "dura") -> None:
        self.domain_id = domain_id
        qos = Qos(Policy.Userdata(data=b"enclave=/;"), Policy.EntityName(name))
        try:
            self._dp = DomainParticipant(domain_id, qos)
        except DDSException as e:
            raise BusError(f"cannot join DDS domain {domain_id}: {e} (check CYCLONEDDS_URI)") from e
        self._mine: list[Entity] = [self._dp]  # every wrapper we made, deleted with us
        self._topics: dict[str, Topic[Any]] = {}
        self._sinks: dict[int, tuple[bool, Callable[[], list[Any]], OnSamples]] = {}
        self._lock = threading.Lock()
        ref = self._dp._ref
        self._waitset = _C.create_waitset(ref)
        self._guard = _C.create_guard(ref)
        _C.attach(self._waitset, self._guard, 0)
        self._stopping = False
        self._ids = itertools.count(1)
        self._thread = threading.Thread(target=self._run, name="ros2-receive", daemon=True)
        self._thread.start()

    @property
    def guid(self) -> bytes:
        """Return the participant's GUID (16 bytes), its ROS 2 gid."""
        return bytes(self._dp.guid.bytes)

    @property
    def closed(self) -> bool:
        return self._stopping

    def unique_id(self) -> bytes:
        """Make a 16-byte id no other endpoint pair has: this participant's GUID prefix and a
        counter (as rmw_cyclonedds names its clients and services)."""
        with self._lock:
            return self.guid[:12] + next(self._ids).to_bytes(4, "big")

    # --- entities -------------------------------------------------------------------

    def _topic(self, name: str, data_type: type[IdlStruct]) -> Topic[Any]:
        topic = self._topics.get(name)
        if topic is None:
            topic = self._topics[name] = Topic(self._dp, name, data_type)
            self._mine.append(topic)
        elif topic.data_type is not data_type:
            raise BusError(f"DDS topic '{name}' is already used with another type")
        return topic

    def reader(
        self,
        topic: str,
        data_type: type[IdlStruct],
        qos: Qos,
        on_samples: OnSamples,
        *,
        first: bool = False,
    ) -> Reader:
        """Read a DDS topic: its raw samples (``(bytes, SampleInfo)``) go to ``on_samples``.

        Raises:
            BusError: DDS refused the reader.
        """
        with self._lock:
            self._check_open()
            try:
                entity = DataReader(self._dp, self._topic(topic, data_type), qos)
            except DDSException as e:
                raise BusError(f"cannot read DDS topic '{topic}': {e}") from e
            ref = entity._ref

            def take() -> list[Any]:
                found = ddspy_take(ref, _ANY, _BATCH)
                return found if isinstance(found, list) else []  # an int: deleted meanwhile

            return self._attach(Reader(self, entity, topic), take, on_samples, first)

    def builtin_reader(self, kind: str, on_samples: OnSamples) -> Reader:
        """Read what DDS discovery finds: ``participant``, ``publication`` or ``subscription``.

        Its samples are :class:`Announcement` objects; it is served first in a wake-up.
        """
        with self._lock:
            self._check_open()
            entity = BuiltinDataReader(self._dp, _BUILTIN[kind])

            def take() -> list[Any]:
                try:
                    return [_announcement(s) for s in entity.take(_BATCH)]
                except DDSException:
                    return []

            return self._attach(Reader(self, entity, f"DCPS{kind}"), take, on_samples, True)

    def _attach(
        self, reader: Reader, take: Callable[[], list[Any]], on: OnSamples, first: bool
    ) -> Reader:
        self._mine.append(reader.entity)
        condition = _C.create_readcondition(reader.handle, _ANY)
        self._sinks[reader.handle] = (first, take, on)
        _C.attach(self._waitset, condition, reader.handle)
        return reader

    def writer(self, topic: str, data_type: type[IdlStruct], qos: Qos) -> Writer:
        """Write one type on one DDS topic.

        Raises:
            BusError: DDS refused the writer.
        """
        with self._lock:
            self._check_open()
            try:
                entity = DataWriter(self._dp, self._topic(topic, data_type), qos)
            except DDSException as e:
                raise BusError(f"cannot write DDS topic '{topic}': {e}") from e
            self._mine.append(entity)
            return Writer(self, entity, topic)

    def _check_open(self) -> None:
        if self._stopping:
            raise BusError(f"the DDS participant of domain {self.domain_id} is closed")

    def _delete(self, endpoint: Reader | Writer) -> None:
        with self._lock:
            if self._stopping or endpoint.entity not in self._mine:
                return
            self._mine.remove(endpoint.entity)
            ref = endpoint.entity._ref
            self._sinks.pop(ref, None)
            self._forget(endpoint.entity)
            _C.delete(ref)  # its read condition goes with it, and leaves the waitset

    @staticmethod
    def _forget(entity: Entity) -> None:
        # the binding deletes an entity when its wrapper is collected; a wrapper we
        # deleted ourselves must not try again (its handle could be reused by then)
        Entity._entities.pop(entity._ref, None)

    # --- reception ------------------------------------------------------------------

    def _run(self) -> None:
        capacity = 64
        fired = (ct.c_ssize_t * capacity)()
        timeout = duration(seconds=1)
        while not self._stopping:
            count = _C.wait(self._waitset, fired, capacity, timeout)
            if count <= 0 or self._stopping:
                continue
            sinks = self._sinks
            ready = [sinks[h] for h in fired[: min(count, capacity)] if h in sinks]
            ready.sort(key=lambda sink: not sink[0])  # discovery first
            for _, take, on_samples in ready:
                while True:
                    samples = take()
                    if not samples:
                        break
                    try:
                        on_samples(samples, time.time())
                    except Exception:
                        log.exception("handling DDS samples failed")
                    if len(samples) < _BATCH:
                        break

    # --- the end --------------------------------------------------------------------

    def close(self) -> None:
        """Stop receiving and delete the participant and every entity in it (idempotent)."""
        with self._lock:
            if self._stopping:
                return
            self._stopping = True
            _C.set_guard(self._guard, True)
        if threading.current_thread() is not self._thread:
            self._thread.join()
        with self._lock:
            for entity in self._mine:
                self._forget(entity)
            self._mine.clear()
            self._sinks.clear()
            self._topics.clear()
            _C.delete(self._dp._ref)  # with everything in it

    def __enter__(self) -> Participant:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
