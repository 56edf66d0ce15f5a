"""Which files are checked together: a robot description with its domain, problem,
integrity and repair rules; or a PDDL domain (and a problem of it) on its own.

A robot description names its files (``domain:``, ``problem:``, ``integrity:``,
``rules:``); the server finds the descriptions in the workspace, so that a domain opened
alone is still checked against the robot that uses it.
"""

from __future__ import annotations

import os
import re
from collections.abc import Iterable, Iterator, Mapping
from dataclasses import dataclass
from pathlib import Path

import yaml

from knowledge.sources import read_text

_SKIPPED = frozenset({".git", ".venv", "venv", "node_modules", "__pycache__", "build", "dist"})
_MAX_SCANNED = 2000  # files looked at per workspace folder: a huge tree is not read whole
_ROBOT_KEY = re.compile(r"^robot\s*:", re.MULTILINE)
_DOMAIN_NAME = re.compile(r"\(\s*define\s*\(\s*domain\s+([^\s()]+)", re.IGNORECASE)
_PROBLEM_DOMAIN = re.compile(r"\(\s*:domain\s+([^\s()]+)", re.IGNORECASE)


@dataclass(frozen=True)
class Project:
    """The files checked together; ``robot`` is ``None`` for PDDL on its own, or for a
    YAML file that no robot names (a standalone observers file, checked as ``dura
    validate`` checks one: ``alone``) or an ASP program (``alone``: its syntax)."""

    robot: Path | None
    domain: Path | None
    problems: tuple[Path, ...] = ()
    rule_files: tuple[Path, ...] = ()
    alone: Path | None = None

    @property
    def files(self) -> tuple[Path, ...]:
        found = [self.robot, self.domain, *self.problems, *self.rule_files, self.alone]
        return tuple(dict.fromkeys(p for p in found if p is not None))


def is_robot_text(text: str) -> bool:
    """Whether a YAML text is a robot description (it has a top-level ``robot:``)."""
    return _ROBOT_KEY.search(text) is not None


def _paths(value: object, folder: Path) -> tuple[Path, ...]:
    values = value if isinstance(value, list) else [value]
    return tuple((folder / v).resolve() for v in values if isinstance(v, str) and v)


def robot_project(robot: Path, text: str) -> Project:
    """The files a robot description names (those it names wrongly are left out: the
    description's own check reports them)."""
    try:
        data = yaml.safe_load(text)
    except yaml.YAMLError:
        data = None
    if not isinstance(data, dict):
        return Project(robot, None)
    folder = robot.parent
    domains = _paths(data.get("domain"), folder)
    rules = _paths(data.get("integrity"), folder) + _paths(data.get("rules"), folder)
    return Project(
        robot, domains[0] if domains else None, _paths(data.get("problem"), folder), rules
    )


def domain_name(text: str) -> str | None:
    """The name a domain file declares, lower-case."""
    found = _DOMAIN_NAME.search(text)
    return found.group(1).lower() if found else None


def problem_domain(text: str) -> str | None:
    """The domain a problem file names, lower-case; ``None`` if it is no problem."""
    found = _PROBLEM_DOMAIN.search(text)
    return found.group(1).lower() if found else None


def yaml_files(folders: Iterable[Path]) -> Iterator[Path]:
    """The YAML files below ``folders`` (at most :data:`_MAX_SCANNED` per folder)."""
    for folder in folders:
        seen = 0
        for root, dirs, files in os.walk(folder):
            dirs[:] = [d for d in dirs if d not in _SKIPPED and not d.startswith(".")]
            for name in files:
                seen += 1
                if seen > _MAX_SCANNED:
                    break
                if name.endswith((".yaml", ".yml")):
                    yield Path(root, name).resolve()
            if seen > _MAX_SCANNED:
                break


def find_robots(folders: Iterable[Path]) -> list[Path]:
    """The robot descriptions below ``folders``."""
    found = []
    for path in yaml_files(folders):
        try:
            if path.stat().st_size < 1_000_000 and is_robot_text(read_text(path)):
                found.append(path)
        except (OSError, UnicodeDecodeError):
            continue
    return found


def projects_of(
    path: Path, robots: Mapping[Path, Project], texts: Mapping[Path, str]
) -> list[Project]:
    """The projects a file belongs to: the robots that name it, else the file on its own
    (a PDDL problem with its domain; an ASP program, whichever rules file names it)."""
    path = path.resolve()
    mine = [p for p in robots.values() if path in p.files]
    if mine:
        return mine
    if path.suffix.lower() in (".yaml", ".yml", ".lp"):
        return [Project(None, None, alone=path)]
    if path.suffix.lower() != ".pddl":
        return []
    text = texts.get(path) or _read(path)
    wanted = problem_domain(text)
    if wanted is None:
        return [Project(None, path)]
    for written in [*texts, *sorted(path.parent.glob("*.pddl"))]:
        candidate = written.resolve()
        if candidate.suffix.lower() == ".pddl" and candidate != path:
            other = texts.get(candidate) or _read(candidate)
            if domain_name(other) == wanted:
                return [Project(None, candidate, (path,))]
    return []


def _read(path: Path) -> str:
    try:
        return read_text(path)
    except (OSError, UnicodeDecodeError):
        return ""
