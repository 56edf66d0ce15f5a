"""The observer extension point: configuration, lifecycle, results, and the registry of types.

An observer watches topics or nodes and, once per loop (``main_loop_rate``, Hz), says
what state each of its resources is in: one :class:`ObserverResult` per topic (and
caller-id group) or node. It reports nothing for ``start_up_time`` seconds after
it is started, nor before its first loop.

An observer type is an :class:`Observer` subclass with a canonical ``type`` name (the
``type`` of its observations). The built-in types and their aliases are listed below;
third-party types register a class under the entry-point group ``dura.observers``
(name = its ``type``; its ``aliases`` are honoured), loaded when an unknown type is
first looked up; a plugin that fails to load is a warning naming it.

Messages reach an observer through the handlers of :meth:`Observer.inputs`, called on
the bus's threads: they only queue. Everything else (filters, checks) happens in
:meth:`Observer.observe`, on the manager's loop thread. Times are robot time (the wall
clock unless ``DURA_TIME_SCALE`` is set, see :mod:`monitoring.robot_time`): the ``now`` of
a loop and the ``received`` (and ``sent``) times of messages. They are exact integer
nanoseconds since the epoch (:meth:`Observer.observe_ns`, ``self.now_ns``,
``self.started_ns``, ``message.received_ns``): an observer subtracts those and turns the
difference into seconds, since seconds since the epoch as floats are 240 ns apart and
a silence of exactly the timeout would not compare as one. The hooks also get ``now``
in float seconds, as before.
"""

from __future__ import annotations

import builtins
import functools
import importlib
import logging
from abc import ABC, abstractmethod
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from importlib.metadata import entry_points
from typing import Annotated, Any, ClassVar

from executive.bus.message import Message
from executive.bus.payloads import ObservationInfo
from knowledge.conventions import Above, AtLeast
from knowledge.errors import ConfigError, did_you_mean
from monitoring.state import Verdict

log = logging.getLogger("dura.observers")

ENTRY_POINT_GROUP = "dura.observers"

Handler = Callable[[Message], None]
StateOf = Callable[[str], Any]  # component name -> its last Lifecycle, or None


@dataclass(frozen=True, kw_only=True)
class ObserverConfig:
    """What every observer configuration has; types add their own fields (the schema of
    the configuration, read by :mod:`knowledge.typed_reader`)."""

    type: str  # the type's canonical name (the entry's ``type`` may be an alias)
    start_up_time: Annotated[float, AtLeast(0.0)] = 0.0
    main_loop_rate: Annotated[float | None, Above(0.0)] = None  # None: the type's default


@dataclass(frozen=True)
class Environment:
    """What an observer may know of the robot besides its messages.

    Args:
        owner: the component whose observer this is (None: an observer of its own).
        behavior: the owner's name if it is a behavior (movement observers blame it).
        component_state: the last lifecycle state the launcher reported for a component.
    """

    owner: str | None = None
    behavior: str | None = None
    component_state: StateOf = field(default=lambda name: None)


@dataclass(frozen=True)
class ObserverResult:
    """One observation and the measured values behind it (e.g. ``{"frequency": 9.98}``)."""

    info: ObservationInfo
    values: Mapping[str, float] = field(default_factory=dict)

    def to_payload(self, observer: str = "") -> dict[str, Any]:
        """The ``observations`` payload: ObservationInfo plus ``values`` and ``observer`` (id)."""
        return {**self.info.to_payload(), "values": dict(self.values), "observer": observer}


class Observer(ABC):
    """One configured observer: it receives messages and reports.

    A type names the schema of its configuration, ``config_type``: a frozen keyword-only
    dataclass extending :class:`ObserverConfig`, whose annotations say what a valid entry
    holds (with ``after_read`` for checks across its fields)."""

    type: ClassVar[str]
    aliases: ClassVar[tuple[str, ...]] = ()  # other names of a plugin's type
    config_type: ClassVar[builtins.type[ObserverConfig]] = ObserverConfig

    def __init__(self, config: ObserverConfig, environment: Environment | None = None) -> None:
        self.config = config
        self.environment = environment or Environment()
        self.started = 0.0  # seconds since the epoch
        self.started_ns = 0  # the same, exact
        self.now_ns = 0  # the loop being observed (exact)

    # --- the type's parts -----------------------------------------------------------

    @abstractmethod
    def _observe(self, now: float) -> list[ObserverResult]:
        """Drain the queued messages and report every resource."""

    def inputs(self) -> list[tuple[str, Handler]]:
        """The bus keys this observer listens to, each with a handler (a key may repeat)."""
        return []

    def _reset(self, now: float) -> None:  # noqa: B027 - an optional hook
        """Forget all measurements (hook of :meth:`start`)."""

    # --- lifecycle ------------------------------------------------------------------

    @property
    def period(self) -> float:
        """Seconds between two loops."""
        return 1.0 / (self.config.main_loop_rate or self.default_rate())

    def default_rate(self) -> float:
        """The loop rate when the configuration gives none."""
        return 1.0

    @property
    def first_report(self) -> float:
        """Seconds from start to the first report: the start-up time, at least one loop."""
        return max(self.config.start_up_time, self.period)

    def start(self, now: float) -> None:
        """Start observing afresh (on activation); ``now`` in seconds since the epoch."""
        self.start_ns(round(now * 1e9))

    def start_ns(self, now_ns: int) -> None:
        """Start observing afresh; ``now_ns`` in integer nanoseconds since the epoch."""
        self.started_ns, self.started = now_ns, now_ns / 1e9
        self._reset(self.started)

    def observe(self, now: float) -> list[ObserverResult]:
        """Report every resource; nothing during the start-up time. ``now`` in seconds."""
        return self.observe_ns(round(now * 1e9))

    def observe_ns(self, now_ns: int) -> list[ObserverResult]:
        """Report every resource; nothing during the start-up time. ``now_ns`` in
        integer nanoseconds since the epoch."""
        self.now_ns = now_ns
        results = self._observe(now_ns / 1e9)
        up = now_ns - self.started_ns >= round(self.config.start_up_time * 1e9)
        return results if up else []

    def since(self, then_ns: int) -> float:
        """Seconds from ``then_ns`` to the loop being observed, exact to the nanosecond."""
        return (self.now_ns - then_ns) / 1e9

    def result(
        self,
        resource: tuple[str, ...],
        verdict: Verdict,
        now: float,
        *,
        values: Mapping[str, float] | None = None,
        callerids: tuple[str, ...] = (),
    ) -> ObserverResult:
        """An observation of this observer's type."""
        info = ObservationInfo(
            self.type, resource, verdict.number, verdict.name, verdict.detail, callerids, now
        )
        return ObserverResult(info, values or {})


# --- the registry ------------------------------------------------------------------------

BUILT_IN = {
    "resources": "monitoring.observers.resources:ResourcesObserver",
    "component": "monitoring.observers.component:ComponentObserver",
    "frequency": "monitoring.observers.frequency:FrequencyObserver",
    "timeout": "monitoring.observers.timeout:TimeoutObserver",
    "timing": "monitoring.observers.timing:TimingObserver",
    "timestamp": "monitoring.observers.timestamp:TimestampObserver",
    "scores": "monitoring.observers.scores:ScoresObserver",
    "movement": "monitoring.observers.movement:MovementObserver",
}
ALIASES = {"activated": "component", "hz": "frequency", "value": "scores", "velocity": "movement"}


def _check(found: object, target: str) -> type[Observer]:
    if not (isinstance(found, type) and issubclass(found, Observer)):
        raise TypeError(f"{target} is not an Observer subclass")
    return found


@functools.cache
def _built_in(name: str) -> type[Observer]:
    module, _, attribute = BUILT_IN[name].partition(":")
    return _check(getattr(importlib.import_module(module), attribute), BUILT_IN[name])


@functools.cache
def _plugins() -> tuple[dict[str, type[Observer]], dict[str, str]]:
    """The observer types of installed plugins, and their aliases (loaded once)."""
    types: dict[str, type[Observer]] = {}
    aliases: dict[str, str] = {}
    for point in entry_points(group=ENTRY_POINT_GROUP):
        if point.name in BUILT_IN or point.name in ALIASES:
            log.warning(
                "observer plugin '%s' (%s) shadows a built-in type; ignored",
                point.name,
                point.value,
            )
            continue
        try:
            loaded = _check(point.load(), point.value)
            if loaded.type != point.name:
                raise TypeError(f"its class says type '{loaded.type}'")
            types[point.name] = loaded
        except Exception as e:
            log.warning("cannot load observer plugin '%s' (%s): %s", point.name, point.value, e)
            continue
        for alias in types[point.name].aliases:
            aliases.setdefault(alias, point.name)
    return types, aliases


def canonical_type(name: str) -> str:
    """The canonical name of an observer type or alias (``hz`` -> ``frequency``)."""
    if name in ALIASES:
        return ALIASES[name]
    if name in BUILT_IN:
        return name
    return _plugins()[1].get(name, name)


def observer_class(name: str) -> type[Observer] | None:
    """The class of an observer type or alias; ``None`` if no type has that name."""
    name = canonical_type(name)
    if name in BUILT_IN:
        return _built_in(name)
    return _plugins()[0].get(name)


def make_observer(config: ObserverConfig, environment: Environment | None = None) -> Observer:
    """A new observer of a configuration's type.

    Raises:
        ConfigError: no observer type has the configuration's type name.
    """
    kind = observer_class(config.type)
    if kind is None:
        raise ConfigError(unknown_type(config.type))
    return kind(config, environment)


def type_names() -> list[str]:
    """Every observer type name and alias, plugins included."""
    types, aliases = _plugins()
    return sorted({*BUILT_IN, *ALIASES, *types, *aliases})


def unknown_type(name: str) -> str:
    """The message for an unknown observer type."""
    names = type_names()
    return f"unknown observer type '{name}' (choose from {', '.join(names)}){did_you_mean(name, names)}"
