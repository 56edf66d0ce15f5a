"""Read a robot description from YAML into :class:`RobotDescription`.

Reading reports every problem it finds (type errors, unknown keys, missing fields)
as a :class:`Finding` with its line; cross-checks between components, and with the
PDDL domain, are in :mod:`knowledge.validation`. :class:`RobotFile` is the schema of
the file; the component, task and planner schemas are those of
:mod:`knowledge.description`.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Annotated, Any

from knowledge.conventions import (
    Check,
    Exists,
    Label,
    Named,
    OneOrMore,
    OrDefault,
    Required,
)
from knowledge.description import (
    DEFAULT_ENDPOINT,
    SAFE_NAME,
    SAFE_NAME_RULE,
    BehaviorSpec,
    FunctionalitySpec,
    PlannerSpec,
    RobotDescription,
    TaskSpec,
)
from knowledge.errors import ConfigError
from knowledge.finding import Finding, Report
from knowledge.ros2_spec import Ros2Spec
from knowledge.sensing_spec import SensingRuleSpec, unique_names
from knowledge.typed_reader import Entry, read
from knowledge.yamlsource import DocumentSource, read_file

__all__ = ["BusSpec", "RobotFile", "load_robot", "read_robot"]

Files = Annotated[tuple[Annotated[Path, Exists()], ...], OneOrMore()]  # each must exist


@dataclass(frozen=True)
class BusSpec:
    """How the robot's processes reach each other."""

    endpoint: Annotated[str, OrDefault()] = DEFAULT_ENDPOINT


@dataclass(frozen=True)
class RobotFile:
    """A robot description as written; paths are resolved against its folder."""

    robot: Annotated[str, Required()] = ""
    domain: Annotated[Files, Required()] = ()
    problem: Files = ()
    planner: PlannerSpec = PlannerSpec()  # noqa: RUF009 - frozen: one default for all
    bus: BusSpec = BusSpec()
    knowledge_base: Path | None = None
    rules: Files = ()
    integrity: Files = ()
    functionalities: Annotated[Mapping[str, FunctionalitySpec], Named("functionality '{name}'")] = (
        field(default_factory=dict)
    )
    behaviors: Annotated[Mapping[str, BehaviorSpec], Named("behavior '{name}'")] = field(
        default_factory=dict
    )
    tasks: Annotated[Mapping[str, TaskSpec], Named("task '{name}'")] = field(default_factory=dict)
    ros2: Ros2Spec | None = None
    objects: Annotated[  # each PDDL object's properties, for goal fields
        Mapping[str, Mapping[str, Any]], Named("the properties of object '{name}'")
    ] = field(default_factory=dict)
    sensing: Annotated[tuple[SensingRuleSpec, ...], Label("sensing rule"), Check(unique_names)] = ()

    def after_read(self, entry: Entry) -> RobotFile:
        """Name the robot after its file if the description does not; check the name."""
        name = self.robot or Path(str(entry.source.context)).stem
        if not SAFE_NAME.fullmatch(name):
            entry.error("robot", f"robot name '{name}' {SAFE_NAME_RULE}")
        return dataclasses.replace(self, robot=name)


def read_robot(
    path: Path, text: str | None = None
) -> tuple[RobotDescription | None, list[Finding]]:
    """Read a robot description, reporting every problem found while reading.

    Returns the description (``None`` if it is unusable) and the findings; a
    description is returned even with errors so that later checks can still run.
    """
    path = Path(path)
    report = Report(str(path))
    found = read_file(path, report, text)
    if found is None:
        if not report.findings:
            report.error(None, "is empty")
        return None, report.findings
    base = path.resolve().parent
    source = DocumentSource(found, report, folder=base, context=path)
    written = read(RobotFile, found.value, source, "the robot description")
    if written is None:
        return None, report.findings
    robot = RobotDescription(
        name=written.robot,
        path=path.resolve(),
        domain=next(iter(written.domain), base / "domain.pddl"),
        functionalities=written.functionalities,
        behaviors=written.behaviors,
        tasks=written.tasks,
        problem=next(iter(written.problem), None),
        rules=written.rules,
        integrity=written.integrity,
        planner=written.planner,
        endpoint=written.bus.endpoint,
        knowledge_base=written.knowledge_base,
        ros2=written.ros2,
        objects=written.objects,
        sensing=written.sensing,
    )
    return robot, report.findings


def load_robot(path: Path, *, domain: bool = True) -> RobotDescription:
    """Read and fully validate a robot description (its domain included, unless
    ``domain`` is false: then its PDDL is checked by whoever parses it).

    Raises:
        ConfigError: with the first problem; ``dura validate`` lists them all.
    """
    from knowledge.validation import validate  # it reads descriptions with read_robot

    result = validate(Path(path), domain=domain)
    errors = [f for f in result.findings if f.is_error]
    if errors or result.robot is None:
        more = (
            f" (and {len(errors) - 1} more: run 'dura validate {path}')" if len(errors) > 1 else ""
        )
        raise ConfigError(f"{errors[0]}{more}" if errors else f"{path}: unusable")
    return result.robot
