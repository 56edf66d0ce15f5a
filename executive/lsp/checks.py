"""The checks of ``dura validate`` and ``dura domain check``, run on a project's open
texts, with their findings grouped by file."""

from __future__ import annotations

import re
from collections.abc import Mapping, Sequence
from pathlib import Path

from executive.cli.validate import check_rule_files
from executive.lsp.project import Project
from executive.planning.domain_check import check_domain
from executive.planning.integrity import check_rules_alone
from knowledge.asp import Asp
from knowledge.errors import AspError, DomainError
from knowledge.finding import Finding, Report, finding_of
from knowledge.sources import Memo, read_text, unsaved
from knowledge.validation import validate
from monitoring.observer_config import check_observer_file, check_observers
from monitoring.repair.rule import read_rules

_RULES_KEY = re.compile(r"^(rules|asp)\s*:", re.MULTILINE)  # a repair rules file
_GOALS_KEY = re.compile(r"^goals\s*:", re.MULTILINE)  # an integrity rules file


def check(
    project: Project, texts: Mapping[Path, str], memo: Memo | None = None
) -> dict[Path, list[Finding]]:
    """Every finding about the project's files, by resolved path (an empty list for a
    file with none, so that an editor clears what it showed); ``texts``: the editor's
    unsaved documents, read instead of their files; ``memo``: what the PDDL reader
    parsed before, by text."""
    findings: list[Finding] = []
    with unsaved(texts, memo):
        if project.robot is not None:
            findings += _robot_findings(project.robot)
        elif project.alone is not None:
            findings += _alone_findings(project.alone)
        elif project.domain is not None:
            findings += _domain_findings(
                project.domain, project.problems[0] if project.problems else None
            )
    by_file: dict[Path, list[Finding]] = {p: [] for p in project.files}
    seen: set[tuple[Path, int | None, str]] = set()
    for f in findings:
        path = Path(f.path).resolve()
        key = (path, f.line, f.message)
        if key not in seen:
            seen.add(key)
            by_file.setdefault(path, []).append(f)
    return by_file


def _robot_findings(robot_path: Path) -> list[Finding]:
    """As ``dura validate``, then ``dura domain check`` of its domain and problem."""
    result = validate(robot_path)
    findings = list(result.findings)
    robot = result.robot
    if robot is None:
        return findings
    findings += check_observers(robot)
    if result.domain is not None and not any(f.is_error for f in findings):
        findings += check_rule_files(robot, result.domain)
    if result.domain is not None:
        findings += _domain_findings(robot.domain, robot.problem)
    return findings


def _domain_findings(domain: Path, problem: Path | None) -> list[Finding]:
    try:
        return check_domain(domain, problem)
    except DomainError as e:
        return [finding_of(e, str(domain))]


def _alone_findings(path: Path) -> list[Finding]:
    """A YAML file no robot names: an observers file as ``dura validate`` checks one; a
    repair rules file as it checks a robot's, with the clingo syntax of its ASP files;
    an integrity rules file as far as it can be without the robot and its domain. An
    ASP program: its clingo syntax."""
    if path.suffix.lower() == ".lp":
        return _asp_findings([path])
    observers = check_observer_file(path)
    if observers is not None:
        return observers[1]
    text = read_text(path)
    report = Report(str(path))
    if _GOALS_KEY.search(text) is not None and _RULES_KEY.search(text) is None:
        check_rules_alone(path, report)
        return report.findings
    if _RULES_KEY.search(text) is None:
        return []
    rules = read_rules(path, report)
    return report.findings + _asp_findings(rules.asp)


def _asp_findings(programs: Sequence[Path]) -> list[Finding]:
    """The clingo syntax errors of ASP programs, at their line and column."""
    findings = []
    for program in programs:
        try:
            Asp().load(program)
        except AspError as e:
            findings.append(finding_of(e, str(program)))
    return findings
