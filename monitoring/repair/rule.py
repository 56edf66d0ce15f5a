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

import dataclasses
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Annotated, Any, TypeVar

from executive.bus.payloads import ObservationInfo
from knowledge.conventions import (
    AtLeast,
    Convert,
    Default,
    EntryLine,
    Exists,
    Key,
    OneOrMore,
    OrDefault,
    Required,
)
from knowledge.errors import ConfigError, DuraError, did_you_mean
from knowledge.finding import Report
from knowledge.typed_reader import MISSING, Entry, Place, open_entry, read_entry
from knowledge.yamlsource import DocumentSource, read_file
from monitoring.diagnosis.model import observer_type
from monitoring.repair.action import ALIASES, Action, action_types

VERDICTS = ("failed", "ok")


def _verdict(value: Any, place: Place) -> Any:
    """A number, ``failed`` or ``ok``."""
    if (isinstance(value, int) and not isinstance(value, bool)) or value in VERDICTS:
        return value
    return place.wrong("a number, 'failed' or 'ok'", value)


C = TypeVar("C", "ObservationCondition", "FaultCondition")


def _window(condition: C, entry: Entry) -> C:
    """The condition with its window (``occurrences`` unless given), if not smaller."""
    window = condition.window if condition.window is not None else condition.occurrences
    if window < condition.occurrences:
        entry.error(
            "window_size",
            f"'window_size' of {entry.what} ({window}) is smaller than 'occurrences' "
            f"({condition.occurrences})",
        )
    return dataclasses.replace(condition, window=window)


Occurrences = Annotated[int, AtLeast(1)]
Window = Annotated[int, Key("window_size"), AtLeast(1), Default(None)]
Resources = Annotated[tuple[str, ...], Key("resource"), OneOrMore(), Required()]


@dataclass(frozen=True)
class ObservationCondition:
    """Observations of one observer that match: a number, a verdict or a message.

    It holds when at least ``occurrences`` of the newest ``window`` observations of
    that observer match; with no observation yet it is unknown.
    """

    type: str  # canonical observer type
    resource: Annotated[tuple[str, ...], OneOrMore(), Required()] = ()
    # a number, 'failed', 'ok', or None (any: the message alone decides)
    observation: Annotated[int | str | None, Convert(_verdict)] = "failed"
    message: Annotated[str | None, Key("observation_msg")] = None
    occurrences: Occurrences = 1
    window: Window = 1
    line: Annotated[int, EntryLine()] = 0

    def after_read(self, entry: Entry) -> ObservationCondition | None:
        """The condition with its observer type's canonical name."""
        found = _window(self, entry)
        if self.message is not None and not entry.has("observation"):
            found = dataclasses.replace(found, observation=None)
        try:
            return dataclasses.replace(found, type=observer_type(self.type).value)
        except DuraError as e:
            entry.error("type", f"{entry.what}: {e}")
            return None

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

    resources: Resources = ()
    occurrences: Occurrences = 1
    window: Window = 1
    line: Annotated[int, EntryLine()] = 0

    def after_read(self, entry: Entry) -> FaultCondition | None:
        found: FaultCondition = _window(self, entry)
        return found if found.resources else None


@dataclass(frozen=True)
class Conditions:
    """When a rule fires, as written (the keys of a rule besides its action's)."""

    positive_observations: tuple[ObservationCondition, ...] = ()
    negative_observations: tuple[ObservationCondition, ...] = ()
    positive_possible_faulty_resources: tuple[FaultCondition, ...] = ()
    negative_possible_faulty_resources: tuple[FaultCondition, ...] = ()
    recall_duration: Annotated[float | None, AtLeast(0.0)] = None
    single_shot: bool = False
    priority: int = 0


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


def _rule(value: Any, place: Place) -> Any:
    """A rule: its name, its action (by ``type``), its condition."""
    number = int(place.path[-1]) + 1
    entry = open_entry(value, place.source, place.path, f"rule {number}", place=place)
    if entry is None:
        return MISSING
    name = entry.read("name", Annotated[str, OrDefault()], f"rule{number}")
    entry.what = f"rule '{name}'"
    kind = entry.read("type", str, None, required=True)
    written = entry.read_fields(Conditions)
    action: Action | None = None
    if kind is not None:
        kinds: Mapping[str, type[Action]] = place.source.context
        action_class = kinds.get(ALIASES.get(kind, kind))
        if action_class is None:  # its keys unknown, unknown keys say nothing
            entry.error(
                "type",
                f"rule '{name}' has unknown action type '{kind}'{did_you_mean(kind, sorted(kinds))}",
            )
        else:
            action = read_entry(action_class, entry)
    if action is None or action is MISSING or written is None:
        return MISSING
    return Rule(
        name,
        action,
        written["positive_observations"],
        written["negative_observations"],
        written["positive_possible_faulty_resources"],
        written["negative_possible_faulty_resources"],
        written["recall_duration"],
        written["single_shot"],
        written["priority"],
        entry.line or 0,
    )


@dataclass(frozen=True)
class RulesFile:
    """A rules file as written."""

    rules: tuple[Annotated[Rule, Convert(_rule)], ...] = ()
    asp: Annotated[tuple[Annotated[Path, Exists()], ...], OneOrMore()] = ()


def read_rules(path: Path, report: Report | None = None) -> RuleSet:
    """Read a rules file; every problem goes to ``report``.

    Raises:
        ConfigError: the file is invalid (the first problem), when no report is given.
    """
    own = report is None
    report = report or Report(str(path))
    rules: list[Rule] = []
    asp: tuple[Path, ...] = ()
    found = read_file(path, report)
    if found is not None:
        source = DocumentSource(found, report, folder=path.parent, context=action_types())
        top = open_entry(found.value, source, what="the rules file")
        if top is not None:
            written = top.read_fields(RulesFile)
            rules_read: tuple[Rule, ...] = written["rules"] if written else ()
            asp = written["asp"] if written else ()
            for rule in rules_read:
                if any(r.name == rule.name for r in rules):
                    report.error(rule.line, f"rule '{rule.name}' is defined twice")
                rules.append(rule)
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
