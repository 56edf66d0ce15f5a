"""The robot description: typed, frozen data read from a robot's YAML file.

A robot has functionalities (components that run until stopped and provide
capabilities), behaviors (components that run a goal to completion) and tasks
(the mapping of a PDDL action onto a behavior and its goal). The annotations are the
schema of the YAML (:mod:`knowledge.typed_reader` reads by them); see
``knowledge/robot.py`` for reading and validating a description.
"""

from __future__ import annotations

import enum
import importlib
import itertools
import re
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any

from knowledge.conventions import (
    AllLines,
    AtLeast,
    Check,
    Convert,
    EntryLine,
    FromKey,
    KeyLines,
    Label,
    Named,
    OneOrMore,
    Open,
    OrDefault,
    Whole,
)
from knowledge.errors import ConfigError

if TYPE_CHECKING:  # read only for a ROS 2 robot: the command line stays quick to start
    from knowledge.ros2_components import Ros2ComponentSpec
    from knowledge.ros2_spec import Ros2Spec
    from knowledge.sensing_spec import SensingRuleSpec
    from knowledge.typed_reader import Entry, Place


_LATER = {  # imported when first asked for (a robot without ROS 2 never imports them)
    "Ros2ComponentSpec": "knowledge.ros2_components",
    "Ros2Spec": "knowledge.ros2_spec",
    "SensingRuleSpec": "knowledge.sensing_spec",
}


def __getattr__(name: str) -> Any:
    """The types of the ROS 2 and sensing parts, for the reader of the annotations."""
    if name in _LATER:
        return getattr(importlib.import_module(_LATER[name]), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


DEFAULT_ENDPOINT = "tcp/127.0.0.1:7447"

# Names become file names (knowledge base, logs) and bus keys: no path or key syntax.
SAFE_NAME = re.compile(r"[A-Za-z][A-Za-z0-9_-]{0,63}")
SAFE_NAME_RULE = "must be a letter, then up to 63 letters, digits, '_' or '-'"
SAFE_TOPIC = re.compile(r"/?[A-Za-z_][A-Za-z0-9_]*(/[A-Za-z_][A-Za-z0-9_]*)*")
SAFE_TOPIC_RULE = "must be names of letters, digits and '_' joined by '/' (a ROS topic name)"
AUTO = "auto"  # the first installed engine that supports the problem
PORTFOLIO = "portfolio"  # several engines at once, the first (or best) plan
DEFAULT_ENGINE = AUTO
ENGINES = (AUTO, PORTFOLIO, "kairos", "aries", "fast-downward", "tamer")
METRIC = re.compile(r"(minimize|maximize)\s+(makespan|\(.*\))", re.DOTALL)
PYTHONS = ("python", "python3")  # in a command: the executive's own interpreter
# a topic pattern: names, '*' (any one name) or '**' (any names, none too) joined by '/'
_PART = r"(?:[A-Za-z_][A-Za-z0-9_]*|\*\*?)"
SAFE_TOPIC_PATTERN = re.compile(rf"/?{_PART}(?:/{_PART})*")
SAFE_TOPIC_PATTERN_RULE = (
    "must be a topic name or a pattern: names, '*' (any one name) or '**' (any names) "
    "joined by '/', with no '**' beside another '*' or '**'"
)


def is_topic_pattern(text: str) -> bool:
    """Whether a text of ``may_subscribe`` is a topic name or pattern (Zenoh's canonical
    form: no ``**`` beside another wildcard)."""
    parts = text.strip("/").split("/")
    wild = ("*", "**")
    beside = any("**" in (a, b) and a in wild and b in wild for a, b in itertools.pairwise(parts))
    return SAFE_TOPIC_PATTERN.fullmatch(text) is not None and not beside


def topic_matches(pattern: str, topic: str) -> bool:
    """Whether a topic pattern of ``may_subscribe`` stands for a topic name (``*`` one
    name, ``**`` any names, none too)."""
    wildcard = {"*": "/[^/]+", "**": "(?:/[^/]+)*"}
    parts = pattern.strip("/").split("/")
    expression = "".join(wildcard.get(part, "/" + re.escape(part)) for part in parts)
    return re.fullmatch(expression, "/" + topic.strip("/")) is not None


class Kind(enum.Enum):
    FUNCTIONALITY = "functionality"
    BEHAVIOR = "behavior"


@dataclass(frozen=True)
class ObserverSpec:
    """One observer entry in the thesis/tug schema (thesis 6.2.5), kept as written.

    ``lines`` maps the dotted path of every key and list item inside the entry
    (``topics.0.callerids.0.filter.window_size``) to its line, so that whoever
    interprets the configuration can report ``file:line`` errors.
    """

    type: str
    config: Annotated[Mapping[str, Any], Whole()]
    line: Annotated[int, EntryLine()] = 0
    lines: Annotated[Mapping[str, int], AllLines()] = field(
        default_factory=dict, compare=False, repr=False
    )

    def line_of(self, path: str) -> int:
        """The line of a dotted path, or of its nearest enclosing entry."""
        while path:
            if path in self.lines:
                return self.lines[path]
            path = path.rpartition(".")[0]
        return self.line


def _ros2(value: Any, place: Place) -> Any:
    from knowledge.ros2_components import read_component_ros2  # only for a ROS 2 component

    return read_component_ros2(value, place)


Texts = Annotated[tuple[str, ...], OneOrMore()]  # a single text is a list of one


@dataclass(frozen=True)
class ComponentSpec:
    """What functionalities and behaviors have in common."""

    name: Annotated[str, FromKey()]
    command: Texts = ()  # needed unless dura's own client runs it (a ROS 2 action, service)
    requires: Texts = ()
    publishes: Texts = ()
    subscribes: Texts = ()
    may_subscribe: Texts = ()  # more topics it may read, not its inputs: names, '*', '**'
    params: Mapping[str, Any] = field(default_factory=dict)
    observers: Annotated[
        tuple[Annotated[ObserverSpec, Open()], ...], Label("observer in {what}")
    ] = ()
    startup_timeout: Annotated[float, AtLeast(0.0)] = 10.0
    line: Annotated[int, EntryLine()] = 0
    lines: Annotated[Mapping[str, int], KeyLines()] = field(
        default_factory=dict, compare=False, repr=False
    )
    # a ROS 2 program, or a ROS 2 action or service
    ros2: Annotated[Ros2ComponentSpec | None, Convert(_ros2)] = None
    host: str | None = None  # the computer whose host agent runs it (None: the executive's)

    @property
    def kind(self) -> Kind:
        raise NotImplementedError

    def after_read(self, entry: Entry) -> ComponentSpec:
        """Report a missing ``command`` (a ROS 2 action or service needs none)."""
        if not entry.has("command") and (self.ros2 is None or self.ros2.call is None):
            entry.error(None, f"{entry.what} has no 'command'")
        return self

    def line_of(self, key: str) -> int:
        """The line of one of this component's keys (its own line if absent)."""
        return self.lines.get(key, self.line)


@dataclass(frozen=True)
class FunctionalitySpec(ComponentSpec):
    """A continuously running component that provides capabilities."""

    provides: Texts = ()
    shareable: bool = True
    rating: Annotated[float, AtLeast(0.0)] = 1.0
    max_faults: Annotated[int, AtLeast(1)] = 3
    standby: bool = False  # kept running, paused, while no task needs it: a warm spare

    @property
    def kind(self) -> Kind:
        return Kind.FUNCTIONALITY


@dataclass(frozen=True)
class BehaviorSpec(ComponentSpec):
    """A component that executes one goal and returns a result."""

    interruptible: bool = True
    reconfigurable: bool = True
    max_restarts: Annotated[int, AtLeast(0)] = 2

    @property
    def kind(self) -> Kind:
        return Kind.BEHAVIOR


@dataclass(frozen=True)
class GoalArg:
    """A behavior goal field: an action parameter (``?to``), a property of the object a
    parameter names (``?to.pose``: ``property`` is ``pose``) or a constant."""

    parameter: str | None = None
    constant: Any = None
    property: str | None = None  # a dotted path into the object's properties

    def resolve(
        self, bindings: Mapping[str, str], objects: Mapping[str, Mapping[str, Any]] | None = None
    ) -> Any:
        """Fill in the field for one step's objects.

        Raises:
            ConfigError: the object has no such property.
        """
        if self.parameter is None:
            return self.constant
        name = bindings[self.parameter]
        if self.property is None:
            return name
        value: Any = (objects or {}).get(name, {})
        for part in self.property.split("."):
            if not isinstance(value, Mapping) or part not in value:
                raise ConfigError(
                    f"object '{name}' has no property '{self.property}' (for ?{self.parameter}"
                    f".{self.property}; declare it under 'objects:' in the robot description)"
                )
            value = value[part]
        return value

    @staticmethod
    def written(value: Any, place: Place) -> Any:
        """A goal field as written: ``?parameter``, ``?parameter.property`` or a constant."""
        if isinstance(value, str) and value.startswith("?"):
            parameter, _, prop = value[1:].partition(".")  # ?to.pose: a property of ?to
            return GoalArg(parameter=parameter, property=prop or None)
        if isinstance(value, Mapping | list):
            return place.wrong("a ?parameter or a constant", value)
        return GoalArg(constant=value)


@dataclass(frozen=True)
class TaskSpec:
    """A PDDL action carried out by a behavior."""

    action: Annotated[str, FromKey()]
    behavior: str
    goal: Annotated[
        Mapping[str, Annotated[GoalArg, Convert(GoalArg.written)]],
        Named("goal field '{name}' of {what}"),
    ] = field(default_factory=dict)
    line: Annotated[int, EntryLine()] = 0
    lines: Annotated[Mapping[str, int], KeyLines("goal")] = field(
        default_factory=dict, compare=False, repr=False
    )


def _engine(engine: str, place: Place) -> str:
    """Report an engine that is neither built in nor a plugin (``dura.planners``)."""
    if engine in ENGINES:
        return engine
    from importlib.metadata import entry_points  # slow to load: only for another engine

    plugins = sorted(ep.name for ep in entry_points(group="dura.planners"))
    if engine not in plugins:
        place.entry.error(
            place.key,
            f"unknown planner engine '{engine}' (choose from {', '.join((*ENGINES, *plugins))})",
        )
    return engine


def _engines(engines: tuple[str, ...], place: Place) -> tuple[str, ...]:
    """Report a portfolio engine that is unknown, or a portfolio in a portfolio."""
    for engine in engines:
        if engine in (AUTO, PORTFOLIO):
            place.entry.error(place.key, f"a portfolio runs engines, not '{engine}'")
        _engine(engine, place)
    return engines


def _metric(metric: str, place: Place) -> str:
    """Report a metric that is not ``minimize|maximize makespan|(expression)``."""
    if not METRIC.fullmatch(metric.strip()):
        place.entry.error(
            place.key,
            f"metric '{metric}' must be 'minimize makespan', 'minimize (total-cost)' or "
            "'minimize|maximize (function objects...)'",
        )
    return metric.strip()


@dataclass(frozen=True)
class PlannerSpec:
    """``planner:``: the engine (``auto``, ``portfolio`` or a name), the engines of the
    portfolio (all installed ones if none), the search timeout and what plans optimise."""

    engine: Annotated[str, OrDefault(), Check(_engine)] = DEFAULT_ENGINE
    timeout: Annotated[float, AtLeast(0.1)] = 30.0
    portfolio: Annotated[tuple[str, ...], OneOrMore(), Check(_engines)] = ()
    metric: Annotated[str | None, Check(_metric)] = None


@dataclass(frozen=True)
class RobotDescription:
    """A whole robot; paths are absolute, resolved against the YAML file's folder."""

    name: str
    path: Path
    domain: Path
    functionalities: Mapping[str, FunctionalitySpec] = field(default_factory=dict)
    behaviors: Mapping[str, BehaviorSpec] = field(default_factory=dict)
    tasks: Mapping[str, TaskSpec] = field(default_factory=dict)
    problem: Path | None = None
    rules: tuple[Path, ...] = ()
    integrity: tuple[Path, ...] = ()
    planner: PlannerSpec = PlannerSpec()
    endpoint: str = DEFAULT_ENDPOINT
    knowledge_base: Path | None = None
    ros2: Ros2Spec | None = None  # the robot's ROS 2 graph, if it has one
    objects: Mapping[str, Mapping[str, Any]] = field(default_factory=dict)  # their properties
    sensing: tuple[SensingRuleSpec, ...] = ()  # facts and values read from topics

    @property
    def components(self) -> dict[str, ComponentSpec]:
        """Every component by name, functionalities first."""
        out: dict[str, ComponentSpec] = dict(self.functionalities)
        out.update(self.behaviors)
        return out

    def component(self, name: str) -> ComponentSpec:
        return self.components[name]

    @property
    def hosts(self) -> list[str]:
        """Every host a component is placed on (``host:``), sorted; the executive's own
        computer is not one of them."""
        return sorted({c.host for c in self.components.values() if c.host is not None})

    def placed_on(self, host: str | None) -> list[str]:
        """The components placed on a host (``None``: the executive's computer)."""
        return [name for name, c in self.components.items() if c.host == host]

    @property
    def capabilities(self) -> list[str]:
        """Every capability some functionality provides, sorted."""
        return sorted({c for f in self.functionalities.values() for c in f.provides})

    def providers(self, capability: str) -> list[FunctionalitySpec]:
        """The functionalities that provide a capability, highest rating first."""
        found = [f for f in self.functionalities.values() if capability in f.provides]
        return sorted(found, key=lambda f: (-f.rating, f.name))

    @property
    def topics(self) -> list[str]:
        """Every topic some component publishes or subscribes, sorted."""
        names: set[str] = set()
        for c in self.components.values():
            names.update(c.publishes, c.subscribes)
        return sorted(names)

    def kb_path(self, cwd: Path | None = None) -> Path:
        """Where this robot's knowledge base lives (default ``./.dura/<robot>.db``)."""
        if self.knowledge_base is not None:
            return self.knowledge_base
        return (cwd or Path.cwd()) / ".dura" / f"{self.name}.db"
