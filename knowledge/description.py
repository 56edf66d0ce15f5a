"""The robot description: typed, frozen data read from a robot's YAML file.

A robot has functionalities (components that run until stopped and provide
capabilities), behaviors (components that run a goal to completion) and tasks
(the mapping of a PDDL action onto a behavior and its goal). See
``knowledge/robot.py`` for reading and validating it.
"""

from __future__ import annotations

import enum
import re
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

from knowledge.errors import ConfigError

if TYPE_CHECKING:  # read only for a ROS 2 robot: the command line stays quick to start
    from knowledge.ros2_components import Ros2ComponentSpec
    from knowledge.ros2_spec import Ros2Spec
    from knowledge.sensing_spec import SensingRuleSpec


DEFAULT_ENDPOINT = "tcp/127.0.0.1:7447"

# Names become file names (knowledge base, logs) and bus keys: no path or key syntax.
SAFE_NAME = re.compile(r"[A-Za-z][A-Za-z0-9_-]{0,63}")
SAFE_NAME_RULE = "must be a letter, then up to 63 letters, digits, '_' or '-'"
SAFE_TOPIC = re.compile(r"/?[A-Za-z_][A-Za-z0-9_]*(/[A-Za-z_][A-Za-z0-9_]*)*")
SAFE_TOPIC_RULE = "must be names of letters, digits and '_' joined by '/' (a ROS topic name)"
DEFAULT_ENGINE = "kairos"
PYTHONS = ("python", "python3")  # in a command: the executive's own interpreter


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
    config: Mapping[str, Any]
    line: int = 0
    lines: Mapping[str, int] = field(default_factory=dict, compare=False, repr=False)

    def line_of(self, path: str) -> int:
        """The line of a dotted path, or of its nearest enclosing entry."""
        while path:
            if path in self.lines:
                return self.lines[path]
            path = path.rpartition(".")[0]
        return self.line


@dataclass(frozen=True)
class ComponentSpec:
    """What functionalities and behaviors have in common."""

    name: str
    command: tuple[str, ...]
    requires: tuple[str, ...] = ()
    publishes: tuple[str, ...] = ()
    subscribes: tuple[str, ...] = ()
    params: Mapping[str, Any] = field(default_factory=dict)
    observers: tuple[ObserverSpec, ...] = ()
    startup_timeout: float = 10.0
    line: int = 0
    lines: Mapping[str, int] = field(default_factory=dict, compare=False, repr=False)
    ros2: Ros2ComponentSpec | None = None  # a ROS 2 program, or a ROS 2 action or service
    host: str | None = None  # the computer whose host agent runs it (None: the executive's)

    @property
    def kind(self) -> Kind:
        raise NotImplementedError

    def line_of(self, key: str) -> int:
        """The line of one of this component's keys (its own line if absent)."""
        return self.lines.get(key, self.line)


@dataclass(frozen=True)
class FunctionalitySpec(ComponentSpec):
    """A continuously running component that provides capabilities."""

    provides: tuple[str, ...] = ()
    shareable: bool = True
    rating: float = 1.0
    max_faults: int = 3
    standby: bool = False  # kept running, paused, while no task needs it: a warm spare

    @property
    def kind(self) -> Kind:
        return Kind.FUNCTIONALITY


@dataclass(frozen=True)
class BehaviorSpec(ComponentSpec):
    """A component that executes one goal and returns a result."""

    interruptible: bool = True
    reconfigurable: bool = True
    max_restarts: int = 2

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


@dataclass(frozen=True)
class TaskSpec:
    """A PDDL action carried out by a behavior."""

    action: str
    behavior: str
    goal: Mapping[str, GoalArg] = field(default_factory=dict)
    line: int = 0
    lines: Mapping[str, int] = field(default_factory=dict, compare=False, repr=False)


@dataclass(frozen=True)
class PlannerSpec:
    engine: str = DEFAULT_ENGINE
    timeout: float = 30.0


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
