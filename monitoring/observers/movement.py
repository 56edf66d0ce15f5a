"""The movement observer (alias ``velocity``): two motion sources that must agree,
e.g. wheel odometry and an IMU, to detect slip (thesis 5.2.2; tug's velocity observer).

Configuration::

    - type: movement
      main_loop_rate: 2.0
      correlations:
        - source_A: {topic: odom, type: odometry}
          source_B: {topic: imu, type: imu}
          rot_z_filter: {type: mean, window_size: 10}      # one filter per compared axis
          behavior: move_to                                 # optional, see below
          states:
            - {state: grip, number: 1, rot_z: {type: gauss, mean: 0.0, std_deviation: 0.1}}

Axes: ``x, y, z`` (linear) and ``rot_x, rot_y, rot_z`` (angular velocity). A source
reads each axis from a field path of its JSON payload; ``type`` gives the usual paths:
``twist`` (``linear.x`` ... ``angular.z``), ``odometry`` (``twist.twist.linear.x`` ...
``twist.twist.angular.z`` as in nav_msgs/Odometry, else ``twist.linear.x`` ...), ``imu``
(``linear_acceleration.x`` ... ``angular_velocity.z``);
``fields: {rot_z: yaw_rate}`` sets or overrides paths, ``callerid`` restricts the
publishers. Linear axes hold whatever the fields hold (a twist's velocity, an IMU's
acceleration): compare them only between sources of the same kind.

Each message from either source is compared with the latest message of the other
(if it is at most ``max_delay`` seconds older, default 0.5): the difference A - B of
every filtered axis goes to that axis' filter, and the states check the filtered
differences. The observation names both topics and, when a failure may also mean the
behavior doing the moving is faulty, that behavior: ``behavior`` if given, else the
observer's component when it is a behavior.
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass
from typing import Annotated, Any

from executive.bus.keys import topic
from executive.bus.message import Message
from knowledge.conventions import Above, Convert, Label
from knowledge.errors import BusError, did_you_mean
from knowledge.typed_reader import MISSING, Place, open_entry
from monitoring.caller_groups import CallerIds, TopicName
from monitoring.field_path import read_number
from monitoring.filter import Filter, FilterConfig, FilterState, Text
from monitoring.observer import Environment, Handler, Observer, ObserverConfig, ObserverResult
from monitoring.state import ObserverState, classify, states_checking

AXES = ("x", "y", "z", "rot_x", "rot_y", "rot_z")


def _paths(*pairs: tuple[str, str]) -> dict[str, tuple[str, ...]]:
    """Each axis' field paths (linear, angular) in order: the first with a number wins."""
    return {
        **{axis: tuple(f"{linear}.{axis}" for linear, _ in pairs) for axis in ("x", "y", "z")},
        **{f"rot_{axis}": tuple(f"{angular}.{axis}" for _, angular in pairs) for axis in "xyz"},
    }


SOURCE_TYPES = {
    "twist": _paths(("linear", "angular")),
    "odometry": _paths(  # nav_msgs/Odometry (a ROS 2 topic), or a flat twist
        ("twist.twist.linear", "twist.twist.angular"), ("twist.linear", "twist.angular")
    ),
    "imu": _paths(("linear_acceleration", "angular_velocity")),
}


@dataclass(frozen=True)
class Source:
    topic: str
    fields: dict[str, tuple[str, ...]]  # axis -> field paths, the first with a number wins
    callerids: tuple[str, ...] = ()


@dataclass(frozen=True)
class Correlation:
    source_a: Source
    source_b: Source
    filters: dict[str, FilterConfig]  # compared axis -> filter
    states: tuple[ObserverState, ...]
    behavior: str | None = None
    max_delay: float = 0.5


@dataclass(frozen=True)
class Fields:
    """The field of a message that holds each axis (a dotted path)."""

    x: Text | None = None
    y: Text | None = None
    z: Text | None = None
    rot_x: Text | None = None
    rot_y: Text | None = None
    rot_z: Text | None = None


def _source(value: Any, place: Place, axes: list[str]) -> Any:
    """A source of motion: its topic, and where each compared axis is in its messages."""
    what = f"{place.key} of {place.entry.what}"
    entry = open_entry(value, place.source, place.path, what, place=place)
    if entry is None:
        return MISSING
    name = entry.read("topic", TopicName, None, required=True)
    kind = entry.read("type", Text, None)
    fields: dict[str, tuple[str, ...]] = {}
    if kind is not None:
        if kind in SOURCE_TYPES:
            fields.update(SOURCE_TYPES[kind])
        else:
            entry.error(
                "type",
                f"unknown source type '{kind}' in {entry.what} (choose from "
                f"{', '.join(SOURCE_TYPES)}, or give 'fields'){did_you_mean(kind, SOURCE_TYPES)}",
            )
    explicit = entry.read("fields", Annotated[Fields, Label("the fields of {what}")], None)
    for axis in AXES if explicit is not None else ():
        if getattr(explicit, axis) is not None:
            fields[axis] = (getattr(explicit, axis),)
    callerids = entry.read("callerid", CallerIds, ())
    entry.close()
    for axis in axes:
        if axis not in fields:
            entry.error(None, f"{entry.what} has no field for the compared axis '{axis}'")
    return Source(name, fields, callerids) if name is not None else MISSING


def _correlation(value: Any, place: Place) -> Any:
    """Two sources whose motions must agree, on the axes it has filters for."""
    entry = open_entry(value, place.source, place.path, place.label or "", place=place)
    if entry is None:
        return MISSING
    filters: dict[str, FilterConfig] = {}
    for axis in AXES:
        label = Label(f"the {axis} filter of {{what}}")
        config = entry.read(f"{axis}_filter", Annotated[FilterConfig, label], None)
        if config is not None:
            filters[axis] = config
    axes = [a for a in AXES if entry.has(f"{a}_filter")]
    if not axes:
        entry.error(None, f"{entry.what} compares no axis (give e.g. 'rot_z_filter')")
    source = Annotated[Source, Convert(lambda v, p: _source(v, p, axes))]
    a = entry.read("source_A", source, None, required=True)
    b = entry.read("source_B", source, None, required=True)
    behavior = entry.read("behavior", Text, None)
    max_delay = entry.read("max_delay", Annotated[float, Above(0.0)], 0.5)
    states = entry.read(
        "states", Annotated[tuple[ObserverState, ...], states_checking(*AXES)], (), required=True
    )
    for state in states:
        for axis in state.checks:
            if axis not in axes:
                entry.error(
                    "states",
                    f"state '{state.name}' of {entry.what} checks '{axis}', which has no filter",
                )
    entry.close()
    if a is None or b is None or not axes or not states:
        return MISSING
    return Correlation(a, b, filters, states, behavior, max_delay)


@dataclass(frozen=True, kw_only=True)
class MovementConfig(ObserverConfig):
    correlations: Annotated[
        tuple[Annotated[Correlation, Convert(_correlation)], ...],
        Label("correlation {n} of the {what}"),
    ]


def _number(payload: dict[str, Any], paths: tuple[str, ...]) -> float | None:
    for path in paths:
        value = read_number(payload, path)
        if value is not None:
            return value
    return None


class _Comparison:
    """The filtered differences of one correlation, from its queued messages."""

    def __init__(self, config: Correlation) -> None:
        self.config = config
        # (received in ns, is B, message)
        self.queue: deque[tuple[int, bool, Message]] = deque()
        self.filters: dict[str, Filter] = {a: f.make() for a, f in config.filters.items()}
        self.latest: list[tuple[int, dict[str, float]] | None] = [None, None]

    def handler(self, is_b: bool) -> Handler:
        callerids = (self.config.source_b if is_b else self.config.source_a).callerids
        append = self.queue.append

        def on_message(message: Message) -> None:
            if not callerids or message.caller_id in callerids:
                append((message.received_ns, is_b, message))

        return on_message

    def reset(self) -> None:
        self.queue.clear()
        for f in self.filters.values():
            f.reset()
        self.latest = [None, None]

    def drain(self) -> None:
        batch = sorted(
            (self.queue.popleft() for _ in range(len(self.queue))), key=lambda item: item[0]
        )
        for received, is_b, message in batch:
            source = self.config.source_b if is_b else self.config.source_a
            try:
                reading = {a: _number(message.payload, source.fields[a]) for a in self.filters}
            except BusError:
                continue
            if any(v is None for v in reading.values()):
                continue
            values = {a: v for a, v in reading.items() if v is not None}
            self.latest[is_b] = (received, values)
            other = self.latest[not is_b]
            if other is None or (received - other[0]) / 1e9 > self.config.max_delay:
                continue
            a_values, b_values = (other[1], values) if is_b else (values, other[1])
            for axis, axis_filter in self.filters.items():
                axis_filter.update(a_values[axis] - b_values[axis])

    def states(self) -> dict[str, FilterState] | None:
        measured = {a: f.state() for a, f in self.filters.items()}
        if any(s is None for s in measured.values()):
            return None
        return {a: s for a, s in measured.items() if s is not None}


class MovementObserver(Observer):
    type = "movement"
    config_type = MovementConfig
    config: MovementConfig

    def __init__(self, config: MovementConfig, environment: Environment | None = None) -> None:
        super().__init__(config, environment)
        self._comparisons = [_Comparison(c) for c in config.correlations]

    def inputs(self) -> list[tuple[str, Handler]]:
        out: list[tuple[str, Handler]] = []
        for comparison in self._comparisons:
            out.append((topic(comparison.config.source_a.topic), comparison.handler(False)))
            out.append((topic(comparison.config.source_b.topic), comparison.handler(True)))
        return out

    def _reset(self, now: float) -> None:
        for comparison in self._comparisons:
            comparison.reset()

    def _observe(self, now: float) -> list[ObserverResult]:
        results: list[ObserverResult] = []
        for comparison in self._comparisons:
            comparison.drain()
            measured = comparison.states()
            if measured is None:
                continue
            config = comparison.config
            resource: tuple[str, ...] = (config.source_a.topic, config.source_b.topic)
            behavior = config.behavior or self.environment.behavior
            if behavior is not None:
                resource += (behavior,)
            verdict = classify(config.states, measured, " (A - B)")
            callerids = tuple(dict.fromkeys(config.source_a.callerids + config.source_b.callerids))
            values = {axis: s.value for axis, s in measured.items()}
            results.append(self.result(resource, verdict, now, values=values, callerids=callerids))
        return results
