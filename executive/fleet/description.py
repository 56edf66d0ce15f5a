"""A fleet description (``fleet.yaml``) as typed, frozen data, read with ``file:line``.

A fleet names its temporal PDDL domain (with a type for robots, ``robot`` by default),
the world it starts from, its planner, where its own bus listens (for operators), and
its robots: each with its robot description, where its executive listens, how the fleet
logs in there (the fleet's login, which the robot's executive writes into
``.dura/<robot>.fleet.bus.json``) and the PDDL object that stands for it. A step is
carried out by the robot its action names: the action's parameter of the robot type,
or the parameter ``actions: {ACTION: {robot: ?p}}`` names. ``facts:`` maps facts of each
robot's own world to facts of the fleet's (:mod:`executive.fleet.robot_facts`).

Reading checks the file alone (:func:`read_fleet`); the checks against the domain and
each robot's description are in :mod:`executive.fleet.validation`.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Annotated

from knowledge.conventions import (
    AtLeast,
    EntryLine,
    Exists,
    FromKey,
    KeyLines,
    Named,
    OrDefault,
    Required,
)
from knowledge.description import SAFE_NAME, SAFE_NAME_RULE, PlannerSpec, RobotDescription
from knowledge.errors import ConfigError
from knowledge.finding import Finding, Report
from knowledge.typed_reader import Entry, read
from knowledge.yamlsource import DocumentSource, read_file

DEFAULT_ROBOT_TYPE = "robot"
DEFAULT_FLEET_ENDPOINT = "tcp/127.0.0.1:7600"
FLEET_USER = "fleet"  # the fleet's login on each robot's bus (executive.bus.security)


def fleet_login_file(folder: Path, robot: str) -> Path:
    """Where a robot's executive writes the fleet's login (the file to copy to the
    fleet's computer), and where the fleet looks for it by default."""
    return folder / ".dura" / f"{robot}.fleet.bus.json"


@dataclass(frozen=True)
class FleetRobot:
    """One robot of the fleet (``robots: {NAME: ...}``); paths are absolute."""

    name: Annotated[str, FromKey()]
    description: Annotated[Path, Required(), Exists()] = Path()
    endpoint: str | None = None  # where its executive listens (default: its description's)
    login: Path | None = None  # the fleet's login there (default: .dura/<robot>.fleet.bus.json)
    object: str | None = None  # its PDDL object (default: its name)
    line: Annotated[int, EntryLine()] = 0
    lines: Annotated[Mapping[str, int], KeyLines()] = field(
        default_factory=dict, compare=False, repr=False
    )

    @property
    def pddl_object(self) -> str:
        return self.object or self.name


@dataclass(frozen=True)
class ActionRobot:
    """``actions: {ACTION: {robot: ?p}}``: the parameter that names an action's robot."""

    action: Annotated[str, FromKey()]
    robot: Annotated[str, Required()] = ""
    line: Annotated[int, EntryLine()] = 0

    @property
    def parameter(self) -> str:
        return self.robot.removeprefix("?")


@dataclass(frozen=True)
class FleetBus:
    """Where the fleet's own bus listens (the operators' commands reach it there)."""

    endpoint: Annotated[str, OrDefault()] = DEFAULT_FLEET_ENDPOINT


@dataclass(frozen=True)
class FleetFile:
    """A fleet description as written."""

    fleet: str = ""
    domain: Annotated[Path, Required(), Exists()] = Path()
    problem: Annotated[Path | None, Exists()] = None
    robot_type: Annotated[str, OrDefault()] = DEFAULT_ROBOT_TYPE
    planner: PlannerSpec = PlannerSpec()  # noqa: RUF009 - frozen: one default for all
    bus: FleetBus = FleetBus()
    knowledge_base: Path | None = None
    max_failures: Annotated[int, AtLeast(1)] = 3  # failed steps in a row: the robot is out
    robots: Annotated[Mapping[str, FleetRobot], Named("robot '{name}'")] = field(
        default_factory=dict
    )
    actions: Annotated[Mapping[str, ActionRobot], Named("action '{name}'")] = field(
        default_factory=dict
    )
    facts: Mapping[str, str] = field(default_factory=dict)  # a robot's fact -> the fleet's
    lines: Annotated[Mapping[str, int], KeyLines("facts")] = field(
        default_factory=dict, compare=False, repr=False
    )

    def after_read(self, entry: Entry) -> FleetFile:
        """Name the fleet after its file if it does not say; check the names."""
        name = self.fleet or Path(str(entry.source.context)).stem
        if not SAFE_NAME.fullmatch(name):
            entry.error("fleet", f"fleet name '{name}' {SAFE_NAME_RULE}")
        if not self.robots:
            entry.error("robots", "a fleet needs at least one robot")
        for robot in self.robots.values():
            if not SAFE_NAME.fullmatch(robot.name):
                entry.source.error(robot.line, f"robot name '{robot.name}' {SAFE_NAME_RULE}")
            if robot.name == name:
                entry.source.error(robot.line, f"robot '{robot.name}' has the fleet's name")
        return dataclasses.replace(self, fleet=name)


@dataclass(frozen=True)
class FleetDescription:
    """A whole fleet; paths are absolute, resolved against the YAML file's folder."""

    name: str
    path: Path
    domain: Path
    problem: Path | None
    robots: Mapping[str, FleetRobot]
    robot_type: str = DEFAULT_ROBOT_TYPE
    planner: PlannerSpec = PlannerSpec()  # noqa: RUF009
    endpoint: str = DEFAULT_FLEET_ENDPOINT
    knowledge_base: Path | None = None
    max_failures: int = 3
    actions: Mapping[str, ActionRobot] = field(default_factory=dict)
    facts: Mapping[str, str] = field(default_factory=dict)
    lines: Mapping[str, int] = field(default_factory=dict, compare=False, repr=False)

    def as_robot(self) -> RobotDescription:
        """The fleet as the high level sees it: a "robot" with the fleet's name, domain,
        world and planner, and no components of its own (its robots carry out the
        steps)."""
        return RobotDescription(
            name=self.name,
            path=self.path,
            domain=self.domain,
            problem=self.problem,
            planner=self.planner,
            endpoint=self.endpoint,
            knowledge_base=self.knowledge_base,
        )

    def robot_of_object(self, name: str) -> FleetRobot | None:
        """The robot a PDDL object stands for (``None``: it is no robot's)."""
        return next((r for r in self.robots.values() if r.pddl_object == name), None)

    def login_file(self, robot: FleetRobot) -> Path:
        return robot.login or fleet_login_file(self.path.parent, robot.name)

    def kb_path(self, cwd: Path | None = None) -> Path:
        """Where the fleet's knowledge base lives (default ``./.dura/<fleet>.db``)."""
        if self.knowledge_base is not None:
            return self.knowledge_base
        return (cwd or Path.cwd()) / ".dura" / f"{self.name}.db"


def is_fleet_file(path: Path) -> bool:
    """Whether a YAML file is a fleet description (its top level has ``fleet:`` or
    ``robots:``), as ``dura validate`` tells one from a robot description."""
    report = Report(str(path))
    found = read_file(path, report)
    value = found.value if found is not None else None
    return isinstance(value, Mapping) and ("fleet" in value or "robots" in value)


def read_fleet(path: Path) -> tuple[FleetDescription | None, list[Finding]]:
    """Read a fleet description, reporting every problem found while reading."""
    path = Path(path)
    report = Report(str(path))
    found = read_file(path, report)
    if found is None:
        if not report.findings:
            report.error(None, "is empty")
        return None, report.findings
    source = DocumentSource(found, report, folder=path.resolve().parent, context=path)
    written = read(FleetFile, found.value, source, "the fleet description")
    if written is None or report.errors:
        return None, report.findings
    fleet = FleetDescription(
        name=written.fleet,
        path=path.resolve(),
        domain=written.domain,
        problem=written.problem,
        robots=written.robots,
        robot_type=written.robot_type,
        planner=written.planner,
        endpoint=written.bus.endpoint,
        knowledge_base=written.knowledge_base,
        max_failures=written.max_failures,
        actions=written.actions,
        facts=written.facts,
        lines=written.lines,
    )
    return fleet, report.findings


def load_fleet(path: Path) -> FleetDescription:
    """Read a fleet description (the file alone).

    Raises:
        ConfigError: with its first problem (``dura validate`` lists them all).
    """
    fleet, findings = read_fleet(path)
    errors = [f for f in findings if f.is_error]
    if errors or fleet is None:
        raise ConfigError(str(errors[0]) if errors else f"{path}: unusable")
    return fleet
