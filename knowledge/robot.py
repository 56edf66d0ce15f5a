"""Read a robot description from YAML into :class:`RobotDescription`.

Reading reports every problem it finds (type errors, unknown keys, missing fields)
as a :class:`Finding` with its line; cross-checks between components, and with the
PDDL domain, are in :mod:`knowledge.validation`.
"""

from __future__ import annotations

from importlib.metadata import entry_points
from pathlib import Path
from typing import Any

import yaml

from knowledge.description import (
    DEFAULT_ENDPOINT,
    SAFE_NAME,
    SAFE_NAME_RULE,
    BehaviorSpec,
    FunctionalitySpec,
    GoalArg,
    Kind,
    ObserverSpec,
    PlannerSpec,
    RobotDescription,
    TaskSpec,
)
from knowledge.errors import ConfigError
from knowledge.finding import Finding, Report
from knowledge.ros2_components import read_component_ros2
from knowledge.ros2_spec import read_ros2
from knowledge.sensing_spec import read_sensing
from knowledge.yamlsource import Section, compose, describe, line_of, paths, to_python

ENGINES = ("kairos", "aries", "fast-downward", "tamer")


def _path(base: Path, value: str | None) -> Path | None:
    if value is None:
        return None
    p = Path(value).expanduser()
    return p if p.is_absolute() else (base / p).resolve()


def _files(top: Section, key: str, base: Path, *, required: bool = False) -> tuple[Path, ...]:
    """Paths under a key, resolved against the description's folder; each must exist."""
    out: list[Path] = []
    for value in top.texts(key, required=required):
        file = _path(base, value)
        if file is None:
            continue
        if not file.is_file():
            top.report.error(top.key_line(key), f"'{key}' names no file: {value}")
        out.append(file)
    return tuple(out)


def _observers(section: Section, key: str, report: Report) -> tuple[ObserverSpec, ...]:
    out: list[ObserverSpec] = []
    for node in section.sequence(key):
        entry = Section(node, f"observer in {section.what}", report)
        if not entry.valid:
            continue
        kind = entry.text("type", required=True)
        if kind is None:
            continue
        config = to_python(node)
        out.append(
            ObserverSpec(kind, config if isinstance(config, dict) else {}, entry.line, paths(node))
        )
    return tuple(out)


def _common(s: Section, report: Report, kind: Kind) -> dict[str, Any]:
    """The fields functionalities and behaviors share."""
    ros2 = read_component_ros2(s.section("ros2"), kind, report)
    program_optional = ros2 is not None and ros2.call is not None  # dura's own client runs it
    return {
        "ros2": ros2,
        "command": s.texts("command", required=not program_optional),
        "requires": s.texts("requires"),
        "publishes": s.texts("publishes"),
        "subscribes": s.texts("subscribes"),
        "params": s.plain("params"),
        "observers": _observers(s, "observers", report),
        "startup_timeout": s.number("startup_timeout", 10.0, minimum=0.0),
        "host": s.text("host"),
        "line": s.line,
        "lines": {k: s.key_line(k) for k in s.written()},
    }


def _functionality(
    name: str, node: yaml.Node, line: int, report: Report
) -> FunctionalitySpec | None:
    s = Section(node, f"functionality '{name}'", report, line)
    if not s.valid:
        return None
    f = FunctionalitySpec(
        name=name,
        provides=s.texts("provides"),
        shareable=s.flag("shareable", True),
        rating=s.number("rating", 1.0, minimum=0.0),
        max_faults=s.integer("max_faults", 3, minimum=1),
        standby=s.flag("standby", False),
        **_common(s, report, Kind.FUNCTIONALITY),
    )
    s.close()
    return f


def _behavior(name: str, node: yaml.Node, line: int, report: Report) -> BehaviorSpec | None:
    s = Section(node, f"behavior '{name}'", report, line)
    if not s.valid:
        return None
    b = BehaviorSpec(
        name=name,
        interruptible=s.flag("interruptible", True),
        reconfigurable=s.flag("reconfigurable", True),
        max_restarts=s.integer("max_restarts", 2, minimum=0),
        **_common(s, report, Kind.BEHAVIOR),
    )
    s.close()
    return b


def _task(action: str, node: yaml.Node, line: int, report: Report) -> TaskSpec | None:
    s = Section(node, f"task '{action}'", report, line)
    if not s.valid:
        return None
    behavior = s.text("behavior", required=True)
    goal: dict[str, GoalArg] = {}
    lines = {k: s.key_line(k) for k in s.written()}
    for field, value, field_line in s.named("goal"):
        lines[f"goal.{field}"] = field_line
        if isinstance(value, yaml.ScalarNode) and value.tag == "tag:yaml.org,2002:str":
            text = str(value.value)
            if text.startswith("?"):
                parameter, _, prop = text[1:].partition(".")  # ?to.pose: a property of ?to
                goal[field] = GoalArg(parameter=parameter, property=prop or None)
                continue
        if not isinstance(value, yaml.ScalarNode):
            report.error(
                line_of(value),
                f"goal field '{field}' of task '{action}' must be a ?parameter or a constant, "
                f"not {describe(value)}",
            )
            continue
        goal[field] = GoalArg(constant=to_python(value))
    s.close()
    if behavior is None:
        return None
    return TaskSpec(action, behavior, goal, s.line, lines)


def _objects(top: Section, report: Report) -> dict[str, dict[str, Any]]:
    """Read ``objects:``: each PDDL object's properties (a mapping), for goal fields."""
    out: dict[str, dict[str, Any]] = {}
    for name, node, line in top.named("objects"):
        value = to_python(node)
        if not isinstance(value, dict):
            report.error(
                line, f"the properties of object '{name}' must be a mapping, not {describe(node)}"
            )
            continue
        out[name] = value
    return out


def _planner(s: Section | None, report: Report) -> PlannerSpec:
    if s is None or not s.valid:
        return PlannerSpec()
    engine = s.text("engine", "kairos") or "kairos"
    plugins = sorted(ep.name for ep in entry_points(group="dura.planners"))
    if engine not in ENGINES and engine not in plugins:
        report.error(
            s.key_line("engine"),
            f"unknown planner engine '{engine}' (choose from {', '.join((*ENGINES, *plugins))})",
        )
    timeout = s.number("timeout", 30.0, minimum=0.1)
    s.close()
    return PlannerSpec(engine, timeout)


def read_robot(
    path: Path, text: str | None = None
) -> tuple[RobotDescription | None, list[Finding]]:
    """Read a robot description, reporting every problem found while reading.

    Returns the description (``None`` if it is unusable) and the findings; a
    description is returned even with errors so that later checks can still run.
    """
    path = Path(path)
    report = Report(str(path))
    node = compose(path, report, text)
    if node is None:
        if not report.findings:
            report.error(None, "is empty")
        return None, report.findings
    top = Section(node, "the robot description", report)
    if not top.valid:
        return None, report.findings
    base = path.resolve().parent
    name = top.text("robot", required=True) or path.stem
    if not SAFE_NAME.fullmatch(name):
        report.error(top.key_line("robot"), f"robot name '{name}' {SAFE_NAME_RULE}")
    domain = next(iter(_files(top, "domain", base, required=True)), None)
    problem = next(iter(_files(top, "problem", base)), None)
    planner = _planner(top.section("planner"), report)
    bus = top.section("bus")
    endpoint = DEFAULT_ENDPOINT
    if bus is not None and bus.valid:
        endpoint = bus.text("endpoint", DEFAULT_ENDPOINT) or DEFAULT_ENDPOINT
        bus.close()
    kb = _path(base, top.text("knowledge_base"))
    rules = _files(top, "rules", base)
    integrity = _files(top, "integrity", base)
    functionalities = {}
    for fname, fnode, fline in top.named("functionalities"):
        f = _functionality(fname, fnode, fline, report)
        if f is not None:
            functionalities[fname] = f
    behaviors = {}
    for bname, bnode, bline in top.named("behaviors"):
        b = _behavior(bname, bnode, bline, report)
        if b is not None:
            behaviors[bname] = b
    tasks = {}
    for action, tnode, tline in top.named("tasks"):
        t = _task(action, tnode, tline, report)
        if t is not None:
            tasks[action] = t
    ros2 = read_ros2(top.section("ros2"), base, report)
    objects = _objects(top, report)
    sensing = read_sensing(top, report)
    top.close()
    robot = RobotDescription(
        name=name,
        path=path.resolve(),
        domain=domain or base / "domain.pddl",
        functionalities=functionalities,
        behaviors=behaviors,
        tasks=tasks,
        problem=problem,
        rules=rules,
        integrity=integrity,
        planner=planner,
        endpoint=endpoint,
        knowledge_base=kb,
        ros2=ros2,
        objects=objects,
        sensing=sensing,
    )
    return robot, report.findings


def load_robot(path: Path, *, domain: bool = True) -> RobotDescription:
    """Read and fully validate a robot description (its domain included, unless
    ``domain`` is false: then its PDDL is checked by whoever parses it).

    Raises:
        ConfigError: with the first problem; ``dura validate`` lists them all.
    """
    from knowledge.validation import validate

    result = validate(Path(path), domain=domain)
    errors = [f for f in result.findings if f.is_error]
    if errors or result.robot is None:
        more = (
            f" (and {len(errors) - 1} more: run 'dura validate {path}')" if len(errors) > 1 else ""
        )
        raise ConfigError(f"{errors[0]}{more}" if errors else f"{path}: unusable")
    return result.robot
