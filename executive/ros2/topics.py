"""ROS 2 topics as a topic source: their samples reach observers as bus messages do.

:class:`Ros2Topics` serves the keys ``topic/<name>`` of the ROS 2 topics a robot
description lists (``ros2: topics:``). For each key in use it keeps one DDS reader
(``rt/<name>``, the topic's QoS) and turns every sample into a :class:`~executive.ros2.message.RosMessage`:
caller id the writer's node (:meth:`Discovery.caller`), ``sent`` the sample's source
timestamp, ``received`` its take, and a ``payload`` decoded from CDR only when read
(frequency and timeout observers never decode). ``stamp`` is ``header.stamp``.

A topic declared without a type is read once a publisher shows its type. A type that
no definition knows, a publisher of another type than the declared one, and a sample
that is not what its type says are each a one-line warning (malformed samples: the
first and every 100th of a topic); the rest of the topic is observed as before.
"""

from __future__ import annotations

import logging
import threading
from dataclasses import dataclass, field
from typing import Any

from executive.bus.keys import topic as topic_key
from executive.bus.session import Handler
from executive.ros2.cdr import CdrError, Decoder
from executive.ros2.discovery import Discovery
from executive.ros2.message import RosMessage
from executive.ros2.names import dds_topic, ros_type
from executive.ros2.participant import Participant, Reader
from executive.ros2.qos import dds_qos
from executive.ros2.types import TypeLibrary
from knowledge.errors import BusError, DuraError
from knowledge.ros2_spec import Ros2Spec, Ros2TopicSpec

log = logging.getLogger("dura.ros2")

READER_DEPTH = 1000  # samples a reader keeps while the receive thread is busy elsewhere


@dataclass
class _Feed:
    """One ROS 2 topic that some handler listens to."""

    key: str
    spec: Ros2TopicSpec
    handlers: tuple[Handler, ...] = ()
    type: str | None = None  # the ROS 2 type it is read as
    decoder: Decoder | None = None
    reader: Reader | None = None
    malformed: int = 0
    warned: set[str] = field(default_factory=set)

    def decode(self, raw: bytes, caller: str) -> dict[str, Any]:
        if self.decoder is None:
            raise BusError(f"{self.key}: no decoder for ROS 2 topic {self.spec.name}")
        try:
            return self.decoder(raw)
        except CdrError as e:
            self.malformed += 1
            if self.malformed == 1 or self.malformed % 100 == 0:
                log.warning(
                    "malformed sample #%d on ROS 2 topic %s from %s: %s",
                    self.malformed, self.spec.name, caller or "?", e,
                )  # fmt: skip
            raise BusError(f"{self.key}: malformed ROS 2 sample ({e})") from e

    def warn_once(self, key: str, message: str) -> None:
        if key not in self.warned:
            self.warned.add(key)
            log.warning("%s", message)


class _Subscription:
    def __init__(self, owner: Ros2Topics, feed: _Feed, handler: Handler) -> None:
        self._owner, self._feed, self._handler = owner, feed, handler

    def undeclare(self) -> None:
        self._owner._unsubscribe(self._feed, self._handler)


class Ros2Topics:
    """The ROS 2 topics of a robot, served to observers as ``topic/<name>`` keys."""

    def __init__(
        self,
        spec: Ros2Spec,
        participant: Participant,
        library: TypeLibrary,
        discovery: Discovery,
    ) -> None:
        self.spec = spec
        self.participant = participant
        self.library = library
        self.discovery = discovery
        self._lock = threading.RLock()
        self._feeds = {topic_key(t.observed_as): _Feed(topic_key(t.observed_as), t)
                       for t in spec.topics.values()}  # fmt: skip
        discovery.on_change(self._resolve)

    def serves(self, key: str) -> bool:
        return key in self._feeds

    @property
    def keys(self) -> list[str]:
        """The keys it serves, one per ROS 2 topic of the robot (``topic/scan``)."""
        return list(self._feeds)

    def definition(self, type: str) -> str:
        """Return the ``ros2msg`` definition of a type, as rosbag2 writes it in a bag."""
        return self.library.definition(type)

    def subscribe(self, key: str, handler: Handler) -> _Subscription:
        """Deliver the samples of a ROS 2 topic to ``handler`` (on the receive thread).

        Raises:
            BusError: not a ROS 2 topic of the robot, or DDS refused the reader.
        """
        feed = self._feeds.get(key)
        if feed is None:
            raise BusError(f"'{key}' is not a ROS 2 topic of the robot")
        with self._lock:
            feed.handlers = (*feed.handlers, handler)
            if feed.reader is None:
                self._open(feed, feed.spec.type)
        return _Subscription(self, feed, handler)

    def _unsubscribe(self, feed: _Feed, handler: Handler) -> None:
        with self._lock:
            feed.handlers = tuple(h for h in feed.handlers if h is not handler)
            if not feed.handlers and feed.reader is not None:
                self._close_reader(feed)

    def _close_reader(self, feed: _Feed) -> None:
        if feed.reader is None:
            return
        guid = feed.reader.guid
        feed.reader.close()
        feed.reader = None
        try:
            self.discovery.retract(guid)
        except DuraError as e:
            log.debug("cannot tell ROS 2 that dura stopped reading %s: %s", feed.spec.name, e)

    def status(self) -> dict[str, dict[str, Any]]:
        """Tell each ROS 2 topic's type (if known), whether it is read, its malformed samples."""
        with self._lock:
            return {
                f.spec.name: {"type": f.type, "reading": f.reader is not None,
                              "handlers": len(f.handlers), "malformed": f.malformed}
                for f in self._feeds.values()
            }  # fmt: skip

    # --- readers --------------------------------------------------------------------

    def _open(self, feed: _Feed, kind: str | None) -> None:
        if kind is None:
            kind = self._discovered_type(feed)
            if kind is None:
                return  # until a publisher shows its type
        feed.type = kind
        feed.decoder = self.library.decoder(kind)
        try:
            feed.reader = self.participant.reader(
                dds_topic(feed.spec.name),
                self.library.idl(kind),
                dds_qos(feed.spec.qos, depth=READER_DEPTH),
                self._deliver(feed),
            )
        except DuraError as e:
            feed.warn_once("reader", f"ROS 2 topic {feed.spec.name} cannot be read: {e}")
            return
        try:
            self.discovery.declare(feed.reader.guid, writer=False)
        except DuraError as e:
            log.warning("cannot tell ROS 2 that dura reads %s: %s", feed.spec.name, e)

    def _discovered_type(self, feed: _Feed) -> str | None:
        found = sorted(self.discovery.types_of(feed.spec.name))
        for dds_name in found:
            known = self.library.of_dds(dds_name)
            if known is not None:
                return known
            feed.warn_once(
                dds_name,
                f"ROS 2 topic {feed.spec.name} has type '{ros_type(dds_name) or dds_name}', "
                f"which neither ROS 2 {self.library.distribution} nor the robot's messages "
                "define; it is not observed",
            )
        return None

    def _resolve(self) -> None:
        """Open readers that waited for a type; warn of publishers of another type.

        Called after every change of the graph.
        """
        with self._lock:
            for feed in self._feeds.values():
                if feed.handlers and feed.reader is None and feed.spec.type is None:
                    self._open(feed, None)
                if feed.type is None:
                    continue
                for dds_name in self.discovery.types_of(feed.spec.name):
                    if ros_type(dds_name) != feed.type:
                        feed.warn_once(
                            "mismatch " + dds_name,
                            f"a publisher of ROS 2 topic {feed.spec.name} sends "
                            f"'{ros_type(dds_name) or dds_name}', not '{feed.type}': DDS does "
                            "not deliver its samples to dura",
                        )

    def _deliver(self, feed: _Feed) -> Any:
        key = feed.key
        caller = self.discovery.caller

        def on_samples(samples: list[Any], received: float) -> None:
            handlers = feed.handlers
            received_ns = round(received * 1e9)
            for data, info in samples:
                if not info.valid_data:
                    continue
                message = RosMessage.at_ns(
                    key,
                    data,
                    caller(info.publication_handle),
                    info.source_timestamp,
                    received_ns,
                    decode=feed.decode,
                    type=feed.type or "",
                )
                for handler in handlers:
                    try:
                        handler(message)
                    except Exception:  # one failing handler must not cost the others
                        log.exception("a handler of ROS 2 topic %s failed", feed.spec.name)

        return on_samples

    def close(self) -> None:
        """Delete every reader (the participant stays)."""
        with self._lock:
            for feed in self._feeds.values():
                self._close_reader(feed)
                feed.handlers = ()
