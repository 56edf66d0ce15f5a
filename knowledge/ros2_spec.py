"""The ``ros2:`` section of a robot description: how dura joins the robot's ROS 2 graph.

Example::

    ros2:
      domain_id: 0                  # ROS_DOMAIN_ID of the robot (default 0)
      distribution: jazzy           # message definitions and wire details (default jazzy)
      transport: dds                # ROS 2 over DDS (the rmw_cyclonedds/rmw_fastrtps wire)
      node: dura                    # the node name dura has in the ROS 2 graph
      messages: [msgs]              # optional: folders or files of custom .msg/.srv/.action
      diagnostics: /diagnostics     # where observations and diagnoses go (null: nowhere)
      events: /dura/events          # where executive events go (null: nowhere)
      goals: /dura/goals            # where ROS 2 tools submit goals (null: nowhere)
      topics:                       # ROS 2 topics that observers may name
        /scan: {type: sensor_msgs/msg/LaserScan, qos: sensor_data}
        /odom: {}                   # type learnt from the publisher (ROS 2 discovery)
        /battery: {type: my_msgs/Battery, qos: {reliability: reliable, depth: 10}}

Observers name a ROS 2 topic as any other (``scan`` or ``/scan``). ``qos`` is a ROS 2
profile name or its policies; dura's reader asks for that reliability and durability
(the default, ``sensor_data``, is best effort: it hears reliable and best-effort
publishers alike).
"""

from __future__ import annotations

import dataclasses
import re
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Annotated, Any

from knowledge.conventions import (
    AtLeast,
    AtMost,
    Check,
    Convert,
    EntryLine,
    FromKey,
    OneOf,
    OneOrMore,
    OrDefault,
)
from knowledge.errors import ConfigError, did_you_mean
from knowledge.ros2_messages import (
    DEFAULT_DISTRIBUTION,
    DISTRIBUTIONS,
    normalize_type,
    read_definitions,
    standard_store,
)
from knowledge.typed_reader import MISSING, Entry, Place, read

TRANSPORTS = ("dds",)
RELIABILITY = ("reliable", "best_effort")
DURABILITY = ("volatile", "transient_local")
HISTORY = ("keep_last", "keep_all")
MAX_DOMAIN_ID = 232  # the largest domain id whose RTPS ports fit (ROS 2 and DDS agree)

_TOKEN = re.compile(r"[A-Za-z_][A-Za-z0-9_]*")


@dataclass(frozen=True)
class QosProfile:
    """The QoS policies ROS 2 sets on an endpoint (rmw_qos_profile_t, the part dura uses)."""

    reliability: str = "reliable"
    durability: str = "volatile"
    history: str = "keep_last"
    depth: int = 10


# The profiles of rmw/qos_profiles.h, by the names rclcpp and rclpy give them.
PROFILES: Mapping[str, QosProfile] = {
    "default": QosProfile(),
    "sensor_data": QosProfile(reliability="best_effort", depth=5),
    "services_default": QosProfile(),
    "parameters": QosProfile(depth=1000),
    "parameter_events": QosProfile(depth=1000),
    "transient_local": QosProfile(durability="transient_local", depth=1),  # latched
}
OBSERVED_PROFILE = "sensor_data"


@dataclass(frozen=True)
class QosSpec:
    """The QoS policies of a topic as written: what is not written is ``sensor_data``'s."""

    reliability: Annotated[str, OrDefault(), OneOf(RELIABILITY, "reliability")] = "best_effort"
    durability: Annotated[str, OrDefault(), OneOf(DURABILITY, "durability")] = "volatile"
    history: Annotated[str, OrDefault(), OneOf(HISTORY, "history")] = "keep_last"
    depth: Annotated[int, AtLeast(1)] = 5


def _qos(value: Any, place: Place) -> Any:
    """A QoS profile: its name, or its policies."""
    if isinstance(value, str):
        if value not in PROFILES:
            return place.error(
                f"unknown QoS profile '{value}' of {place.entry.what} (choose from "
                f"{', '.join(PROFILES)}){did_you_mean(value, PROFILES)}"
            )
        return PROFILES[value]
    what = f"the QoS of {place.entry.what}"
    written = read(QosSpec, value, place.source, what, path=place.path)
    if written is None:
        return MISSING
    return QosProfile(written.reliability, written.durability, written.history, written.depth)


@dataclass(frozen=True)
class Ros2TopicSpec:
    """One ROS 2 topic dura observes: its fully qualified name, type and QoS."""

    name: Annotated[str, FromKey()]  # e.g. /scan
    # e.g. sensor_msgs/msg/LaserScan; None: learnt from discovery
    type: Annotated[str | None, Check(lambda kind, place: normalize_type(kind))] = None
    qos: Annotated[QosProfile, Convert(_qos)] = PROFILES[OBSERVED_PROFILE]
    line: Annotated[int, EntryLine()] = 0

    @property
    def observed_as(self) -> str:
        """Name it as observers do (and its bus key's last part): ``scan``."""
        return self.name.strip("/")


def _node(name: str, place: Place) -> str:
    if not _TOKEN.fullmatch(name):
        place.entry.error(place.key, f"invalid ROS 2 node name '{name}'")
    return name


def _optional_topic(value: Any, place: Place) -> Any:
    """A topic name, or null: none."""
    if value is None:
        return None
    if not isinstance(value, str):
        return place.error(f"'{place.key}' of {place.entry.what} must be a topic name")
    try:
        return topic_name(value)
    except ConfigError as e:
        return place.error(f"'{place.key}' of {place.entry.what}: {e}")


def _topics(value: Any, place: Place) -> Any:
    """The ROS 2 topics observers may name, by observed name."""
    if place.source.blank(value):
        return {}
    if not isinstance(value, Mapping):
        return place.wrong("a mapping of names to entries", value)
    source = place.source
    out: dict[str, Ros2TopicSpec] = {}
    for name, item in value.items():
        path = (*place.path, str(name))
        line = source.key_line(path)
        try:
            full = topic_name(str(name))
        except ConfigError as e:
            source.error(line, str(e))
            continue
        if item is None:
            topic: Ros2TopicSpec | None = Ros2TopicSpec(full, line=line or 0)
        else:
            what = f"ROS 2 topic '{full}'"
            topic = read(Ros2TopicSpec, item, source, what, path=path, line=line, name=full)
        if topic is None:
            continue
        if topic.observed_as in out:
            source.error(line, f"ROS 2 topic '{topic.name}' is listed twice")
        out[topic.observed_as] = topic
    return out


@dataclass(frozen=True)
class Ros2Spec:
    """How dura joins the robot's ROS 2 graph."""

    domain_id: Annotated[int, AtLeast(0), AtMost(MAX_DOMAIN_ID)] = 0
    distribution: Annotated[str, OrDefault(), OneOf(DISTRIBUTIONS, "distribution")] = (
        DEFAULT_DISTRIBUTION
    )
    transport: Annotated[str, OrDefault(), OneOf(TRANSPORTS, "transport")] = "dds"
    node: Annotated[str, OrDefault(), Check(_node)] = "dura"
    messages: Annotated[tuple[Path, ...], OneOrMore()] = ()
    topics: Annotated[Mapping[str, Ros2TopicSpec], Convert(_topics)] = field(
        default_factory=dict
    )  # by observed name
    diagnostics: Annotated[str | None, Convert(_optional_topic)] = "/diagnostics"
    events: Annotated[str | None, Convert(_optional_topic)] = "/dura/events"
    goals: Annotated[str | None, Convert(_optional_topic)] = "/dura/goals"
    line: Annotated[int, EntryLine()] = 0

    def topic(self, observed_as: str) -> Ros2TopicSpec | None:
        """Find the ROS 2 topic observers call ``observed_as`` (``scan`` or ``/scan``)."""
        return self.topics.get(observed_as.strip("/"))

    def after_read(self, entry: Entry) -> Ros2Spec:
        """Read the message definitions (their problems are reported too) and check the
        topics' types against them."""
        store = standard_store(self.distribution)
        definitions, findings = read_definitions(self.messages, store.fielddefs)
        if entry.source.report is not None:
            entry.source.report.findings.extend(findings)
        known = sorted({*store.fielddefs, *definitions})
        topics = dict(self.topics)
        written = entry.written.get("topics")
        for key in written if isinstance(written, Mapping) else ():
            topic = topics.get(str(key).strip("/"))
            if topic is None or topic.type is None or topic.type in known:
                continue
            line = entry.source.key_line((*entry.path, "topics", str(key), "type"))
            entry.source.error(
                line or topic.line,
                f"ROS 2 topic '{topic.name}' has unknown message type '{topic.type}'"
                f"{did_you_mean(topic.type, known)}",
            )
            topics[topic.observed_as] = dataclasses.replace(topic, type=None)
        return dataclasses.replace(self, topics=topics)


def topic_name(name: str) -> str:
    """Qualify a ROS 2 topic name (relative names are in the root namespace).

    Raises:
        ConfigError: not a valid ROS 2 topic name (``~`` and ``{}`` are not supported).
    """
    full = name if name.startswith("/") else "/" + name
    tokens = full[1:].split("/")
    if not full[1:] or not all(_TOKEN.fullmatch(t) for t in tokens):
        raise ConfigError(
            f"invalid ROS 2 topic name '{name}' (tokens of letters, digits and '_', "
            "not starting with a digit, separated by single '/')"
        )
    return full
