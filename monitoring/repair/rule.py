"""Repair rules in the thesis schema (6.3.4), read from YAML with the line of every key.

```yaml
rules:
  - type: restart                # the action (restart, fault, log, mail, process, command,
    component: lidar             #   parameter, goal) and its own keys
    name: restart_lidar          # optional (default rule<N>); ASP rules refer to it
    positive_observations:       # each must hold ...
      - {type: hz, resource: scan, observation: -1, occurrences: 3, window_size: 5}
    negative_observations: []    # ... each must be known not to hold
    positive_possible_faulty_resources:
      - {resource: [lidar, lidar_filter], occurrences: 2}   # a list: any of them
    negative_possible_faulty_resources: []
    recall_duration: 10.0        # fire again after this long while the condition holds
    single_shot: false           # fire at most once
    priority: 0                  # higher first when several rules fire together
    timeout: 10.0                # seconds the action may take
asp: [more_rules.lp]             # optional: rules written in ASP (see rules.lp)
```
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import yaml

from executive.bus.payloads import ObservationInfo
from knowledge.errors import ConfigError, DuraError
from knowledge.finding import Report
from knowledge.yamlsource import Section, compose, describe, did_you_mean, line_of
from monitoring.diagnosis.model import observer_type
from monitoring.repair.action import ALIASES, DEFAULT_TIMEOUT, Action, action_types

VERDICTS = ("failed", "ok")


@dataclass(frozen=True)
class ObservationCondition:
    """Observations of one observer that match: a number, a verdict or a message.

    It holds when at least ``occurrences`` of the newest ``window`` observations of
    that observer match; with no observation yet it is unknown.
    """

    type: str  # canonical observer type
    resource: tuple[str, ...]
    observation: int | str | None = "failed"  # a number, 'failed', 'ok', or None (any)
    message: str | None = None
    occurrences: int = 1
    window: int = 1
    line: int = 0

    @property
    def key(self) -> tuple[str, tuple[str, ...]]:
        return (self.type, self.resource)

    def matches(self, info: ObservationInfo) -> bool:
        if self.message is not None and info.observation_msg != self.message:
            return False
        if self.observation == "failed":
            return info.failed
        if self.observation == "ok":
            return not info.failed
        return self.observation is None or info.observation == self.observation


@dataclass(frozen=True)
class FaultCondition:
    """Holds when any of ``resources`` is possibly faulty (named by some diagnosis) in
    at least ``occurrences`` of the newest ``window`` diagnoses."""

    resources: tuple[str, ...]
    occurrences: int = 1
    window: int = 1
    line: int = 0


@dataclass(frozen=True)
class Rule:
    """A condition (all its parts must hold) and an action."""

    name: str
    action: Action
    positive_observations: tuple[ObservationCondition, ...] = ()
    negative_observations: tuple[ObservationCondition, ...] = ()
    positive_faults: tuple[FaultCondition, ...] = ()
    negative_faults: tuple[FaultCondition, ...] = ()
    recall_duration: float | None = None
    single_shot: bool = False
    priority: int = 0
    line: int = 0

    @property
    def has_condition(self) -> bool:
        return bool(
            self.positive_observations
            or self.negative_observations
            or self.positive_faults
            or self.negative_faults
        )


@dataclass(frozen=True)
class RuleSet:
    """The rules of one file and the ASP files it names."""

    path: Path
    rules: tuple[Rule, ...]
    asp: tuple[Path, ...] = ()


def observation_key(info: ObservationInfo) -> tuple[str, tuple[str, ...]] | None:
    """The (canonical type, resources) an observation is counted under; None if unknown."""
    try:
        return (observer_type(info.type).value, info.resource)
    except DuraError:
        return None


def _window(entry: Section) -> tuple[int, int]:
    occurrences = entry.integer("occurrences", 1, minimum=1)
    window = entry.integer("window_size", occurrences, minimum=1)
    if window < occurrences:
        entry.report.error(
            entry.key_line("window_size"),
            f"'window_size' of {entry.what} ({window}) is smaller than 'occurrences' ({occurrences})",
        )
    return occurrences, window


def _observation(node: yaml.Node, what: str, report: Report) -> ObservationCondition | None:
    entry = Section(node, what, report)
    if not entry.valid:
        return None
    kind = entry.text("type", required=True)
    resource = entry.texts("resource", required=True)
    value: int | str | None = "failed"
    raw = entry.node("observation")
    if raw is not None:
        if isinstance(raw, yaml.ScalarNode) and raw.tag == "tag:yaml.org,2002:int":
            value = int(raw.value)
        elif isinstance(raw, yaml.ScalarNode) and raw.value in VERDICTS:
            value = raw.value
        else:
            report.error(
                line_of(raw),
                f"'observation' of {what} must be a number, 'failed' or 'ok', not {describe(raw)}",
            )
    message = entry.text("observation_msg")
    if message is not None and raw is None:
        value = None  # the message alone decides
    occurrences, window = _window(entry)
    entry.close()
    if kind is None:
        return None
    try:
        canonical = observer_type(kind).value
    except DuraError as e:
        report.error(entry.key_line("type"), f"{what}: {e}")
        return None
    return ObservationCondition(
        canonical, resource, value, message, occurrences, window, entry.line
    )


def _fault(node: yaml.Node, what: str, report: Report) -> FaultCondition | None:
    entry = Section(node, what, report)
    if not entry.valid:
        return None
    resources = entry.texts("resource", required=True)
    occurrences, window = _window(entry)
    entry.close()
    return FaultCondition(resources, occurrences, window, entry.line) if resources else None


def _rule(
    node: yaml.Node, number: int, kinds: dict[str, type[Action]], report: Report
) -> Rule | None:
    entry = Section(node, f"rule {number}", report)
    if not entry.valid:
        return None
    name = entry.text("name", f"rule{number}") or f"rule{number}"
    entry.what = f"rule '{name}'"
    kind = entry.text("type", required=True)

    def conditions(key: str, read: object) -> list[object]:
        found = [read(item, f"'{key}' of rule '{name}'", report) for item in entry.sequence(key)]  # type: ignore[operator]
        return [c for c in found if c is not None]

    positive_observations = conditions("positive_observations", _observation)
    negative_observations = conditions("negative_observations", _observation)
    positive_faults = conditions("positive_possible_faulty_resources", _fault)
    negative_faults = conditions("negative_possible_faulty_resources", _fault)
    recall = entry.number("recall_duration", -1.0, minimum=0.0)
    single_shot = entry.flag("single_shot", False)
    priority = entry.integer("priority", 0)
    timeout = entry.number("timeout", DEFAULT_TIMEOUT, minimum=0.001)
    action: Action | None = None
    if kind is not None:
        action_class = kinds.get(ALIASES.get(kind, kind))
        if action_class is None:
            report.error(
                entry.key_line("type"),
                f"rule '{name}' has unknown action type '{kind}'{did_you_mean(kind, sorted(kinds))}",
            )
        else:
            action = action_class.configure(entry, timeout)
            entry.close()  # without the action's keys known, unknown keys say nothing
    if action is None:
        return None
    return Rule(
        name,
        action,
        tuple(positive_observations),  # type: ignore[arg-type]
        tuple(negative_observations),  # type: ignore[arg-type]
        tuple(positive_faults),  # type: ignore[arg-type]
        tuple(negative_faults),  # type: ignore[arg-type]
        recall if recall >= 0 else None,
        single_shot,
        priority,
        entry.line,
    )


def read_rules(path: Path, report: Report | None = None) -> RuleSet:
    """Read a rules file; every problem goes to ``report``.

    Raises:
        ConfigError: the file is invalid (the first problem), when no report is given.
    """
    own = report is None
    report = report or Report(str(path))
    rules: list[Rule] = []
    asp: list[Path] = []
    node = compose(path, report)
    if node is not None:
        top = Section(node, "the rules file", report)
        if top.valid:
            kinds = action_types()
            for number, item in enumerate(top.sequence("rules"), 1):
                rule = _rule(item, number, kinds, report)
                if rule is None:
                    continue
                if any(r.name == rule.name for r in rules):
                    report.error(rule.line, f"rule '{rule.name}' is defined twice")
                rules.append(rule)
            for name in top.texts("asp"):
                file = (path.parent / name).resolve()
                if not file.is_file():
                    report.error(top.key_line("asp"), f"'asp' names no file: {name}")
                asp.append(file)
            for rule in rules:
                if not rule.has_condition and not asp:
                    report.error(
                        rule.line,
                        f"rule '{rule.name}' has no condition (give it one, or trigger it "
                        "from an ASP file named under 'asp')",
                    )
            if not rules and not report.errors:
                report.warning(top.line, "defines no rules")
            top.close()
    elif not report.errors:
        report.error(None, "is empty")
    if own and report.errors:
        raise ConfigError(str(report.errors[0]))
    return RuleSet(path, tuple(rules), tuple(asp))
