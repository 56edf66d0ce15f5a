"""Check a fleet description against its domain and each of its robots, with
``file:line`` (``dura validate fleet.yaml``; ``dura fleet run`` runs the same checks).

- the domain and problem read; the robot type is one of the domain's types;
- each robot's description is valid, is named as the fleet names it, and its PDDL
  object is in the fleet's problem, of the robot type (or a subtype);
- each action's robot: the parameter ``actions:`` names, else its first parameter of the
  robot type (an action without one completes at once with its effects, a warning);
- each fact mapping reads, and its fleet side is a predicate or function of the domain
  with as many arguments;
- every action a robot may carry out (its object fits the action's robot parameter) has
  a task in that robot's description, whose goal fields name only the action's
  parameters.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path

from executive.fleet.description import FleetDescription, read_fleet
from executive.fleet.robot_facts import FactMapping
from knowledge.description import RobotDescription
from knowledge.domain import DomainInfo, parse_problem, read_domain, type_name
from knowledge.errors import ConfigError, DomainError
from knowledge.finding import Finding, Report, finding_of
from knowledge.sources import read_text
from knowledge.validation import validate


@dataclass(frozen=True)
class FleetCheck:
    """What the checks found: the fleet, its domain, its robots' descriptions, each
    acting action's robot parameter, and the findings (``ok``: no errors)."""

    fleet: FleetDescription | None
    domain: DomainInfo | None = None
    robots: Mapping[str, RobotDescription] = field(default_factory=dict)
    actors: Mapping[str, str] = field(default_factory=dict)  # action -> robot parameter
    objects: Mapping[str, str] = field(default_factory=dict)  # the problem's, name -> type
    findings: tuple[Finding, ...] = ()
    mappings: tuple[FactMapping, ...] = ()  # a robot's facts in the fleet's world

    @property
    def actor_index(self) -> dict[str, int]:
        """Each acting action's robot parameter, by its position among the parameters."""
        if self.domain is None:
            return {}
        actions = self.domain.actions
        return {a: actions[a].parameter_names.index(p) for a, p in self.actors.items()}

    @property
    def outside(self) -> frozenset[str]:
        """The problem's objects of the robot type that are no robot of the fleet."""
        if self.fleet is None or self.domain is None:
            return frozenset()
        fleet, domain = self.fleet, self.domain
        ours = {r.pddl_object for r in fleet.robots.values()}
        return frozenset(
            name
            for name, kind in self.objects.items()
            if domain.is_a(kind, fleet.robot_type) and name not in ours
        )

    @property
    def ok(self) -> bool:
        return self.fleet is not None and not any(f.is_error for f in self.findings)


def check_fleet(path: Path) -> FleetCheck:
    """Read a fleet description and run every check."""
    fleet, findings = read_fleet(Path(path))
    if fleet is None:
        return FleetCheck(None, findings=tuple(findings))
    report = Report(str(path))
    try:
        domain = read_domain(fleet.domain)
    except DomainError as e:
        return FleetCheck(fleet, findings=(*findings, finding_of(e, str(fleet.domain))))
    objects: dict[str, str] = {}
    if fleet.problem is not None:
        try:
            text = read_text(fleet.problem)
            problem = parse_problem(fleet.domain, text, str(fleet.problem), domain_checked=True)
            objects = {o.name: type_name(o.type) for o in problem.all_objects}
        except (OSError, UnicodeDecodeError) as e:
            report.error(fleet.lines.get("problem"), f"cannot read problem {fleet.problem}: {e}")
        except DomainError as e:
            findings.append(finding_of(e, str(fleet.problem)))
    if fleet.robot_type not in domain.types:
        report.error(
            fleet.lines.get("robot_type"),
            f"robot type '{fleet.robot_type}' is no type of domain '{domain.name}' "
            f"(types: {', '.join(domain.types) or 'none'})",
        )
        return FleetCheck(fleet, domain, findings=(*findings, *report.findings))
    actors = _actors(fleet, domain, report)
    mappings = _mappings(fleet, domain, report)
    robots: dict[str, RobotDescription] = {}
    for robot in fleet.robots.values():
        described = _robot(fleet, robot.name, objects, domain, report)
        if described is not None:
            robots[robot.name] = described
            findings += _tasks(
                fleet, described, domain, actors=actors, objects=objects, report=report
            )
    check = FleetCheck(fleet, domain, robots, actors, objects, mappings=mappings)
    for name in sorted(check.outside):
        report.warning(
            fleet.lines.get("robots"),
            f"object '{name}' of type '{objects[name]}' is no robot of the fleet: no plan "
            "gives it a step",
        )
    placed = sorted(findings + report.findings, key=lambda f: (f.path, f.line or 0))
    return dataclasses.replace(check, findings=tuple(placed))


def _actors(fleet: FleetDescription, domain: DomainInfo, report: Report) -> dict[str, str]:
    """Each action's robot parameter (without ``?``); actions without one are left out."""
    actors: dict[str, str] = {}
    for name, given in fleet.actions.items():
        action = domain.actions.get(name)
        if action is None:
            report.error(given.line, f"action '{name}' is no action of domain '{domain.name}'")
        elif given.parameter not in action.parameter_names:
            names = ", ".join("?" + p for p in action.parameter_names) or "none"
            report.error(
                given.line,
                f"action '{name}' has no parameter '?{given.parameter}' (it has {names})",
            )
        else:
            actors[name] = given.parameter
    for name, action in domain.actions.items():
        if name in fleet.actions:
            continue
        found = next(
            (p for p, kind in action.parameters if domain.is_a(kind, fleet.robot_type)), None
        )
        if found is None:
            report.warning(
                fleet.lines.get("domain"),
                f"action '{name}' has no parameter of type '{fleet.robot_type}': no robot "
                "carries it out, it completes at once with its effects",
            )
        else:
            actors[name] = found
    return actors


def _mappings(
    fleet: FleetDescription, domain: DomainInfo, report: Report
) -> tuple[FactMapping, ...]:
    """The fact mappings that read and fit the fleet's domain."""
    found: list[FactMapping] = []
    for robot_side, fleet_side in fleet.facts.items():
        line = fleet.lines.get(f"facts.{robot_side}", fleet.lines.get("facts"))
        try:
            mapping = FactMapping.read(robot_side, fleet_side)
        except ConfigError as e:
            report.error(line, f"fact mapping: {e}")
            continue
        name, arity = mapping.fleet.name, len(mapping.fleet.args)
        kinds = domain.predicates.get(name, domain.functions.get(name))
        if kinds is None:
            report.error(line, f"fact mapping: '{name}' is no predicate or function of "
                               f"domain '{domain.name}'")  # fmt: skip
        elif len(kinds) != arity:
            report.error(line, f"fact mapping: '{name}' takes {len(kinds)} arguments, not "
                               f"{arity}")  # fmt: skip
        else:
            found.append(mapping)
    return tuple(found)


def _robot(
    fleet: FleetDescription,
    name: str,
    objects: Mapping[str, str],
    domain: DomainInfo,
    report: Report,
) -> RobotDescription | None:
    """The robot's description, if it is valid and fits the fleet."""
    robot = fleet.robots[name]
    line = robot.lines.get("description", robot.line)
    result = validate(robot.description)
    errors = [f for f in result.findings if f.is_error]
    if errors or result.robot is None:
        first = errors[0] if errors else f"{robot.description}: unusable"
        report.error(line, f"robot '{name}': its description is not valid: {first}")
        return None
    if result.robot.name != name:
        report.error(line, f"robot '{name}': its description names robot '{result.robot.name}'")
        return None
    kind = objects.get(robot.pddl_object)
    if kind is None:
        where = f"problem {fleet.problem.name}" if fleet.problem is not None else "no problem"
        report.error(
            robot.lines.get("object", robot.line),
            f"robot '{name}' has no object '{robot.pddl_object}' in {where} (declare "
            f"'{robot.pddl_object} - {fleet.robot_type}')",
        )
        return None
    if not domain.is_a(kind, fleet.robot_type):
        report.error(
            robot.lines.get("object", robot.line),
            f"robot '{name}': object '{robot.pddl_object}' is a '{kind}', not a "
            f"'{fleet.robot_type}'",
        )
        return None
    return result.robot


def carries_out(domain: DomainInfo, action: str, actor: str, kind: str) -> bool:
    """Whether an object of type ``kind`` may be the robot of ``action``."""
    wanted = dict(domain.actions[action].parameters)[actor]
    return domain.is_a(kind, wanted)


def _tasks(
    fleet: FleetDescription,
    robot: RobotDescription,
    domain: DomainInfo,
    *,
    actors: Mapping[str, str],
    objects: Mapping[str, str],
    report: Report,
) -> list[Finding]:
    """Every action the robot may carry out has a task in its description, whose goal
    fields name only the fleet action's parameters (those go to the robot's file)."""
    entry = fleet.robots[robot.name]
    kind = objects[entry.pddl_object]
    own = Report(str(robot.path))
    for action, actor in sorted(actors.items()):
        if not carries_out(domain, action, actor, kind):
            continue
        task = robot.tasks.get(action)
        if task is None:
            report.error(
                entry.line,
                f"robot '{robot.name}' may carry out action '{action}' ('{entry.pddl_object}' "
                f"is a '{kind}'), but {robot.path.name} has no task for it",
            )
            continue
        names = domain.actions[action].parameter_names
        for name, arg in task.goal.items():
            if arg.parameter is not None and arg.parameter not in names:
                listed = ", ".join("?" + p for p in names)
                own.error(
                    task.lines.get(f"goal.{name}", task.line),
                    f"goal field '{name}' of task '{action}' names '?{arg.parameter}', which "
                    f"action '{action}' of fleet domain '{domain.name}' lacks (it has {listed})",
                )
    return own.findings
