"""Cross-check a robot description: components among themselves and with the domain.

Each check adds findings to a report; :func:`validate` runs them all on one file
and returns every finding, so ``dura validate`` can list each problem on a line.
"""

from __future__ import annotations

import graphlib
import importlib.util
import os
import shutil
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path

from knowledge.description import (
    PYTHONS,
    SAFE_NAME,
    SAFE_NAME_RULE,
    SAFE_TOPIC,
    SAFE_TOPIC_PATTERN_RULE,
    SAFE_TOPIC_RULE,
    RobotDescription,
    is_topic_pattern,
    topic_matches,
)
from knowledge.domain import DomainInfo, parse_problem, read_domain, type_name
from knowledge.errors import DomainError, did_you_mean
from knowledge.finding import Finding, Report, Severity, finding_of
from knowledge.robot import read_robot
from knowledge.ros2_components import check_ros2_components
from knowledge.sensing_spec import check_sensing
from knowledge.sources import read_text

RESERVED_PREFIXES = ("AB", "/AB")


@dataclass(frozen=True)
class Validation:
    """Everything ``dura validate`` learnt about a robot description."""

    robot: RobotDescription | None
    domain: DomainInfo | None
    findings: tuple[Finding, ...]

    @property
    def errors(self) -> list[Finding]:
        return [f for f in self.findings if f.severity is Severity.ERROR]

    @property
    def warnings(self) -> list[Finding]:
        return [f for f in self.findings if f.severity is Severity.WARNING]

    @property
    def ok(self) -> bool:
        return self.robot is not None and not self.errors


def _reserved(name: str) -> bool:
    return name.startswith(RESERVED_PREFIXES)


def check_names(robot: RobotDescription, report: Report) -> None:
    """Component and topic names are safe (they become file names and bus keys) and none
    starts with AB (the diagnosis engine's own names)."""
    both = set(robot.functionalities) & set(robot.behaviors)
    for name in sorted(both):
        report.error(
            robot.behaviors[name].line,
            f"'{name}' is both a functionality and a behavior; component names must be unique",
        )
    for c in robot.components.values():
        if not SAFE_NAME.fullmatch(c.name):
            report.error(c.line, f"{c.kind.value} name '{c.name}' {SAFE_NAME_RULE}")
        elif _reserved(c.name):
            report.error(c.line, f"{c.kind.value} name '{c.name}' must not start with 'AB'")
        if c.host is not None and not SAFE_NAME.fullmatch(c.host):
            report.error(
                c.line_of("host"), f"host '{c.host}' of {c.kind.value} '{c.name}' {SAFE_NAME_RULE}"
            )
        for key in ("publishes", "subscribes"):
            for topic in getattr(c, key):
                if not SAFE_TOPIC.fullmatch(topic):
                    report.error(
                        c.line_of(key),
                        f"topic '{topic}' of {c.kind.value} '{c.name}' {SAFE_TOPIC_RULE}",
                    )
                elif _reserved(topic):
                    report.error(
                        c.line_of(key),
                        f"topic '{topic}' of {c.kind.value} '{c.name}' must not start with 'AB'",
                    )
        for pattern in c.may_subscribe:
            if not is_topic_pattern(pattern):
                report.error(
                    c.line_of("may_subscribe"),
                    f"may_subscribe '{pattern}' of {c.kind.value} '{c.name}' "
                    f"{SAFE_TOPIC_PATTERN_RULE}",
                )


def check_capabilities(robot: RobotDescription, report: Report) -> None:
    """Every required capability has a provider; `requires` has no cycle."""
    capabilities = robot.capabilities
    for c in robot.components.values():
        for capability in c.requires:
            if not robot.providers(capability):
                report.error(
                    c.line_of("requires"),
                    f"{c.kind.value} '{c.name}' requires unknown capability '{capability}'"
                    f"{did_you_mean(capability, capabilities)}",
                )
    needs = {
        f.name: list(dict.fromkeys(p.name for c in f.requires for p in robot.providers(c)))
        for f in robot.functionalities.values()
    }
    try:
        graphlib.TopologicalSorter(needs).prepare()
        return  # no cycle: networkx (a tenth of a second to import) only names cycles
    except graphlib.CycleError:
        pass
    import networkx as nx

    graph: nx.DiGraph = nx.DiGraph()
    for name, providers in needs.items():
        graph.add_node(name)
        for provider in providers:
            graph.add_edge(name, provider)
    reported: set[frozenset[str]] = set()
    for cycle in nx.simple_cycles(graph):
        key = frozenset(cycle)
        if key in reported:
            continue
        reported.add(key)
        first = robot.functionalities[min(cycle, key=lambda n: robot.functionalities[n].line)]
        start = cycle.index(first.name)
        ring = cycle[start:] + cycle[:start] + [first.name]
        report.error(first.line_of("requires"), f"requires cycle: {' -> '.join(ring)}")


def check_topics(robot: RobotDescription, report: Report) -> None:
    """Warn about subscriptions nobody publishes to."""
    published = {t for c in robot.components.values() for t in c.publishes}
    for c in robot.components.values():
        for pattern in c.may_subscribe:
            if is_topic_pattern(pattern) and not any(topic_matches(pattern, t) for t in published):
                report.warning(
                    c.line_of("may_subscribe"),
                    f"{c.kind.value} '{c.name}' may subscribe to '{pattern}', which no topic "
                    f"a component publishes matches{did_you_mean(pattern, sorted(published))}",
                )
        for topic in c.subscribes:
            if topic not in published:
                report.warning(
                    c.line_of("subscribes"),
                    f"{c.kind.value} '{c.name}' subscribes to '{topic}', which no component "
                    f"publishes{did_you_mean(topic, sorted(published))}",
                )


def check_tasks(
    robot: RobotDescription, domain: DomainInfo, report: Report, domain_report: Report
) -> None:
    """Every task names a domain action, a behavior, and only that action's parameters.

    Actions without a task are reported against the domain file.
    """
    for task in robot.tasks.values():
        action = domain.actions.get(task.action)
        if action is None:
            report.error(
                task.line,
                f"task '{task.action}' names no action of domain '{domain.name}'"
                f"{did_you_mean(task.action, sorted(domain.actions))}",
            )
        if task.behavior not in robot.behaviors:
            report.error(
                task.lines.get("behavior", task.line),
                f"task '{task.action}' names unknown behavior '{task.behavior}'"
                f"{did_you_mean(task.behavior, sorted(robot.behaviors))}",
            )
        if action is None:
            continue
        for field, arg in task.goal.items():
            if arg.parameter is not None and arg.parameter not in action.parameter_names:
                names = ", ".join("?" + p for p in action.parameter_names) or "none"
                report.error(
                    task.lines.get(f"goal.{field}", task.line),
                    f"goal field '{field}' of task '{task.action}' names unknown parameter "
                    f"'?{arg.parameter}' (action '{action.name}' has {names})",
                )
    for name, action in domain.actions.items():
        if name not in robot.tasks:
            domain_report.warning(
                action.line,
                f"action '{name}' has no task in {robot.path.name}: "
                "it will be applied without running a behavior",
            )


def _components_checks(robot: RobotDescription, report: Report) -> None:
    check_names(robot, report)
    check_capabilities(robot, report)
    check_topics(robot, report)
    check_commands(robot, report)
    check_ros2_components(robot, report)


def check_commands(robot: RobotDescription, report: Report) -> None:
    """Each component's command can start on this machine (its program or module
    exists), so a typo is met here and not as a permanent fault at run time."""
    folder = robot.path.parent
    for c in robot.components.values():
        if not c.command and c.ros2 is not None and c.ros2.call is not None:
            continue  # dura's own client of a ROS 2 action or service: no program
        problem = command_problem(c.command, folder)
        if problem:
            report.error(c.line_of("command"), f"{c.kind.value} '{c.name}': {problem}")


def command_problem(argv: tuple[str, ...], folder: Path) -> str:
    """Why an argv cannot start from ``folder``, or an empty string."""
    if not argv:
        return "its command is empty"
    program = argv[0]
    if len(argv) == 1 and len(program.split()) > 1:
        words = ", ".join(program.split())
        return f"command '{program}' is one string with spaces: write it as a list: [{words}]"
    if program in PYTHONS:
        rest = list(argv[1:])
        if rest[:1] == ["-m"]:
            if len(rest) < 2:
                return "command runs 'python -m' without a module"
            return "" if _module_exists(rest[1], folder) else f"no Python module '{rest[1]}'"
        if rest and not rest[0].startswith("-") and not (folder / rest[0]).is_file():
            return f"no Python script '{rest[0]}' in {folder}"
        return ""
    if "/" in program:
        path = folder / program
        if not path.is_file():
            return f"no program '{program}' in {folder}"
        if not os.access(path, os.X_OK):
            return f"program '{program}' is not executable (chmod +x {program})"
        return ""
    if shutil.which(program) is None:
        return f"program '{program}' is not on this machine's PATH"
    return ""


def _module_exists(module: str, folder: Path) -> bool:
    """Whether ``python -m module`` finds it from ``folder``, without importing anything
    of the robot's own code."""
    parts = module.split(".")
    if _module_below(folder, parts):
        return True
    try:
        top = importlib.util.find_spec(parts[0])
    except (ImportError, ValueError):
        return False
    if top is None:
        return False
    if len(parts) == 1:
        return True
    return any(_module_below(Path(p), parts[1:]) for p in top.submodule_search_locations or ())


def _module_below(folder: Path, parts: list[str]) -> bool:
    base = folder.joinpath(*parts)
    return base.with_suffix(".py").is_file() or (base / "__init__.py").is_file()


def validate(path: Path, text: str | None = None, *, domain: bool = True) -> Validation:
    """Read a robot description and run every check, the PDDL domain included unless
    ``domain`` is false (``dura run`` checks the domain in its planner worker, so that
    it starts without unified-planning: :func:`check_domain` on what the worker read)."""
    robot, findings = read_robot(Path(path), text)
    report = Report(str(path))
    info: DomainInfo | None = None
    if robot is not None:
        _components_checks(robot, report)
        if domain and robot.domain.is_file():
            try:
                info = read_domain(robot.domain)
            except DomainError as e:
                findings.append(finding_of(e, str(path)))
        if info is not None:
            objects: dict[str, str] = {}
            if robot.problem is not None and robot.problem.is_file():
                try:
                    text_of_problem = read_text(robot.problem)
                    problem = parse_problem(robot.domain, text_of_problem, str(robot.problem))
                    objects = {o.name: type_name(o.type) for o in problem.all_objects}
                except (OSError, UnicodeDecodeError) as e:
                    report.error(None, f"cannot read problem {robot.problem}: {e}")
                except DomainError as e:
                    findings.append(finding_of(e, str(path)))
            findings.extend(check_domain(robot, info, objects, report))
    all_findings = tuple(sorted(findings + report.findings, key=_order))
    return Validation(robot, info, all_findings)


def check_domain(
    robot: RobotDescription,
    domain: DomainInfo,
    objects: Mapping[str, str],
    report: Report | None = None,
) -> list[Finding]:
    """Check the robot's tasks and sensing rules against its parsed domain and the
    problem's ``objects``: the findings in the domain file; those in the description go
    to ``report`` (or are returned too)."""
    own = report if report is not None else Report(str(robot.path))
    domain_report = Report(str(robot.domain))
    check_tasks(robot, domain, own, domain_report)
    check_sensing(robot, domain, objects, own)
    return [*(own.findings if report is None else ()), *domain_report.findings]


def _order(f: Finding) -> tuple[str, int, int]:
    return (f.path, f.line or 0, 0 if f.is_error else 1)
