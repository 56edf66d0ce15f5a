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

import re
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path

import yaml

from knowledge.errors import ConfigError
from knowledge.finding import Report
from knowledge.ros2_messages import (
    DEFAULT_DISTRIBUTION,
    DISTRIBUTIONS,
    normalize_type,
    read_definitions,
    standard_store,
)
from knowledge.yamlsource import Section, did_you_mean, line_of

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
class Ros2TopicSpec:
    """One ROS 2 topic dura observes: its fully qualified name, type and QoS."""

    name: str  # e.g. /scan
    type: str | None = None  # e.g. sensor_msgs/msg/LaserScan; None: learnt from discovery
    qos: QosProfile = PROFILES[OBSERVED_PROFILE]
    line: int = 0

    @property
    def observed_as(self) -> str:
        """Name it as observers do (and its bus key's last part): ``scan``."""
        return self.name.strip("/")


@dataclass(frozen=True)
class Ros2Spec:
    """How dura joins the robot's ROS 2 graph."""

    domain_id: int = 0
    distribution: str = DEFAULT_DISTRIBUTION
    transport: str = "dds"
    node: str = "dura"
    messages: tuple[Path, ...] = ()
    topics: Mapping[str, Ros2TopicSpec] = field(default_factory=dict)  # by observed name
    diagnostics: str | None = "/diagnostics"
    events: str | None = "/dura/events"
    goals: str | None = "/dura/goals"
    line: int = 0

    def topic(self, observed_as: str) -> Ros2TopicSpec | None:
        """Find the ROS 2 topic observers call ``observed_as`` (``scan`` or ``/scan``)."""
        return self.topics.get(observed_as.strip("/"))


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


def read_ros2(section: Section | None, base: Path, report: Report) -> Ros2Spec | None:
    """Read the ``ros2:`` section; message definition problems are reported too."""
    if section is None or not section.valid:
        return None
    domain_id = section.integer("domain_id", 0, minimum=0)
    if domain_id > MAX_DOMAIN_ID:
        report.error(
            section.key_line("domain_id"),
            f"'domain_id' of {section.what} must be at most {MAX_DOMAIN_ID}, not {domain_id}",
        )
        domain_id = 0
    distribution = _choice(section, "distribution", DISTRIBUTIONS, DEFAULT_DISTRIBUTION)
    transport = _choice(section, "transport", TRANSPORTS, "dds")
    node = section.text("node", "dura") or "dura"
    if not _TOKEN.fullmatch(node):
        report.error(section.key_line("node"), f"invalid ROS 2 node name '{node}'")
    messages = tuple(
        p if p.is_absolute() else (base / p).resolve()
        for p in (Path(t).expanduser() for t in section.texts("messages"))
    )
    diagnostics = _optional_topic(section, "diagnostics", "/diagnostics")
    events = _optional_topic(section, "events", "/dura/events")
    goals = _optional_topic(section, "goals", "/dura/goals")
    entries = list(section.named("topics"))
    section.close()
    store = standard_store(distribution)
    definitions, findings = read_definitions(messages, store.fielddefs)
    for finding in findings:
        report.findings.append(finding)
    known = sorted({*store.fielddefs, *definitions})
    topics: dict[str, Ros2TopicSpec] = {}
    for name, node_, line in entries:
        topic = _topic(name, node_, line, report, known)
        if topic is None:
            continue
        if topic.observed_as in topics:
            report.error(line, f"ROS 2 topic '{topic.name}' is listed twice")
        topics[topic.observed_as] = topic
    return Ros2Spec(
        domain_id,
        distribution,
        transport,
        node,
        messages,
        topics,
        diagnostics,
        events,
        goals,
        section.line,
    )


def _choice(section: Section, key: str, choices: tuple[str, ...], default: str) -> str:
    value = section.text(key, default) or default
    if value not in choices:
        section.report.error(
            section.key_line(key),
            f"unknown {key} '{value}' in {section.what} (choose from {', '.join(choices)})"
            f"{did_you_mean(value, choices)}",
        )
        return default
    return value


def _optional_topic(section: Section, key: str, default: str) -> str | None:
    node = section.node(key)
    if node is None:
        return default
    if isinstance(node, yaml.ScalarNode) and node.tag == "tag:yaml.org,2002:null":
        return None
    if not isinstance(node, yaml.ScalarNode) or node.tag != "tag:yaml.org,2002:str":
        section.report.error(line_of(node), f"'{key}' of {section.what} must be a topic name")
        return default
    try:
        return topic_name(str(node.value))
    except ConfigError as e:
        section.report.error(line_of(node), f"'{key}' of {section.what}: {e}")
        return default


def _topic(
    name: str, node: yaml.Node, line: int, report: Report, known: list[str]
) -> Ros2TopicSpec | None:
    try:
        full = topic_name(name)
    except ConfigError as e:
        report.error(line, str(e))
        return None
    if isinstance(node, yaml.ScalarNode) and node.tag == "tag:yaml.org,2002:null":
        return Ros2TopicSpec(full, line=line)
    s = Section(node, f"ROS 2 topic '{full}'", report, line)
    if not s.valid:
        return None
    kind = s.text("type")
    if kind is not None:
        kind = normalize_type(kind)
        if kind not in known:
            report.error(
                s.key_line("type"),
                f"ROS 2 topic '{full}' has unknown message type '{kind}'"
                f"{did_you_mean(kind, known)}",
            )
            kind = None
    qos = _qos(s)
    s.close()
    return Ros2TopicSpec(full, kind, qos, line)


def _qos(s: Section) -> QosProfile:
    node = s.node("qos")
    if node is None:
        return PROFILES[OBSERVED_PROFILE]
    if isinstance(node, yaml.ScalarNode) and node.tag == "tag:yaml.org,2002:str":
        name = str(node.value)
        if name not in PROFILES:
            s.report.error(
                line_of(node),
                f"unknown QoS profile '{name}' of {s.what} (choose from {', '.join(PROFILES)})"
                f"{did_you_mean(name, PROFILES)}",
            )
            return PROFILES[OBSERVED_PROFILE]
        return PROFILES[name]
    q = Section(node, f"the QoS of {s.what}", s.report)
    if not q.valid:
        return PROFILES[OBSERVED_PROFILE]
    base = PROFILES[OBSERVED_PROFILE]
    profile = QosProfile(
        _choice(q, "reliability", RELIABILITY, base.reliability),
        _choice(q, "durability", DURABILITY, base.durability),
        _choice(q, "history", HISTORY, base.history),
        q.integer("depth", base.depth, minimum=1),
    )
    q.close()
    return profile
