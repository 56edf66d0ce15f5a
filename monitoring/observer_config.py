"""Observer configurations: from robot descriptions, observers files and bus requests.

Every source gives plain mappings in the thesis/tug schema; :func:`read_observer` turns
one into the typed, frozen configuration of its observer type, reporting every
problem as ``file:line: message``. :func:`check_observers` does so for every
observer of a robot (``dura validate`` lists the findings). A standalone observers
file (ported from tug) is a list of observer entries, or a mapping ``setup: [...]``.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

from executive.bus.keys import topic
from knowledge.description import ObserverSpec, RobotDescription
from knowledge.errors import ConfigError, did_you_mean
from knowledge.finding import Finding, Report
from knowledge.typed_reader import MISSING, Source, open_entry, read_entry
from knowledge.yamlsource import read_file
from monitoring.filter import Text
from monitoring.observer import ObserverConfig, make_observer, observer_class, unknown_type

TOPIC_PREFIX = topic("")


def read_observer(value: object, source: Source, owner: str = "") -> ObserverConfig | None:
    """The typed configuration of one observer entry; ``None`` if it has errors (reported).

    ``owner`` names where the entry is, for messages (e.g. ``functionality 'lidar'``).
    """
    suffix = f" of {owner}" if owner else ""
    entry = open_entry(value, source, what=f"observer{suffix}")
    report = source.report
    if entry is None or report is None:
        return None
    errors = len(report.errors)
    name = entry.read("type", Text, None, required=True)
    if name is None:
        return None
    kind = observer_class(name)
    if kind is None:
        entry.error("type", unknown_type(name))
        return None
    entry.what = f"{kind.type} observer{suffix}"
    config = read_entry(kind.config_type, entry, type=kind.type)
    if config is MISSING or len(report.errors) > errors:
        return None
    return config  # type: ignore[no-any-return]


def check_observers(robot: RobotDescription) -> list[Finding]:
    """Read every observer of every component; the findings of all their problems.

    A topic no component publishes or subscribes to, and that is not one of the
    robot's ROS 2 topics, is a warning (a typo, usually).
    """
    report = Report(str(robot.path))
    ros2 = list(robot.ros2.topics) if robot.ros2 is not None else []
    topics = sorted({*robot.topics, *ros2})
    for component in robot.components.values():
        owner = f"{component.kind.value} '{component.name}'"
        for spec in component.observers:
            config = read_observer(spec.config, Source(report, spec.line_of), owner)
            if config is None:
                continue
            keys = dict.fromkeys(key for key, _ in make_observer(config).inputs())
            for key in keys:
                name = key.removeprefix(TOPIC_PREFIX)
                if key.startswith(TOPIC_PREFIX) and name not in topics:
                    report.warning(
                        spec.line,
                        f"the {config.type} observer of {owner} watches topic '{name}', which "
                        f"no component publishes or subscribes to{did_you_mean(name, topics)}",
                    )
    return report.findings


def config_of(
    config: ObserverSpec | Mapping[str, Any], *, path: str = "observer", owner: str = ""
) -> ObserverConfig:
    """The configuration of one entry, for the runtime API.

    Raises:
        ConfigError: the first problem, ``path:line: message``, and how many more there are.
    """
    report = Report(path)
    if isinstance(config, ObserverSpec):
        found = read_observer(config.config, Source(report, config.line_of), owner)
    else:
        found = read_observer(config, Source(report), owner)
    errors = report.errors
    if found is None or errors:
        more = f" (and {len(errors) - 1} more)" if len(errors) > 1 else ""
        raise ConfigError(f"{errors[0]}{more}" if errors else f"{path}: invalid observer")
    return found


def observer_file(path: Path, report: Report) -> list[ObserverSpec] | None:
    """The entries of a standalone observers file (tug form), or ``None`` if it is not one.

    A file is an observers file when its YAML is a list, or a mapping with ``setup``
    and no ``robot``. Problems of the file's shape go to the report.
    """
    found = read_file(path, Report(str(path)))
    if found is None:
        return None
    root = found.value_lines.get("", 1)
    if isinstance(found.value, Mapping):
        keys = {str(k): v for k, v in found.value.items()}
        if "setup" not in keys or "robot" in keys:
            return None
        for key in keys:
            if key != "setup":
                report.error(root, f"unknown key '{key}' in the observers file (only 'setup')")
        items, prefix = keys["setup"], "setup."
    elif isinstance(found.value, list):
        items, prefix = found.value, ""
    else:
        return None
    if not isinstance(items, list):
        line = found.value_lines.get("setup", root)
        report.error(line, "'setup' of the observers file must be a list of observers")
        return []
    specs: list[ObserverSpec] = []
    for i, item in enumerate(items):
        start = f"{prefix}{i}."
        own = {k[len(start) :]: v for k, v in found.key_lines.items() if k.startswith(start)}
        kind = item.get("type") if isinstance(item, Mapping) else None
        line = found.value_lines.get(f"{prefix}{i}", root)
        specs.append(ObserverSpec(str(kind), item, line, own))
    return specs


def check_observer_file(path: Path) -> tuple[list[ObserverSpec], list[Finding]] | None:
    """Read every observer of a standalone observers file: its entries and all problems.

    Returns ``None`` if the file is no observers file (see :func:`observer_file`).
    """
    report = Report(str(path))
    specs = observer_file(path, report)
    if specs is None:
        return None
    for spec in specs:
        read_observer(spec.config, Source(report, spec.line_of))
    return specs, report.findings
