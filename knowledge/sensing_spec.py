"""The ``sensing:`` section of a robot description: facts and values read from topics.

ROSPlan's sensing interface, written as data: each rule watches one field of one topic
(dura's bus, or a ROS 2 topic of the ``ros2:`` section) and keeps a PDDL fact or a
numeric value in the knowledge base in step with it::

    sensing:
      - name: battery_low          # unique (default: the fact or value)
        topic: battery             # a topic a component publishes, or a ROS 2 topic
        field: level               # dotted path in the message (list items by index)
        fact: (battery_low)        # true while the condition holds, false otherwise
        below: 20                  # the condition: below, above or equals (one of them)
        clear_above: 30            # hysteresis: false again only above 30 (with below)
        hold: 2                    # robot seconds a new verdict must last to count
      - topic: battery
        field: level
        value: (battery_level)     # a numeric function: the field's number
        min_change: 1              # only changes of at least 1 are written

``clear_below`` goes with ``above``. ``equals`` compares with a number, a string or a
boolean. Names are checked against the domain and the objects by ``dura validate``
(:mod:`knowledge.validation`); the executive runs the rules
(:mod:`executive.planning.sensing`).
"""

from __future__ import annotations

import dataclasses
import re
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Annotated, Any

from knowledge.conventions import (
    AtLeast,
    Convert,
    Default,
    EntryLine,
    Key,
    KeyLines,
    Required,
    Titles,
)
from knowledge.errors import did_you_mean
from knowledge.finding import Report
from knowledge.typed_reader import Entry, Place

if TYPE_CHECKING:
    from knowledge.description import RobotDescription
    from knowledge.domain import DomainInfo

FIELD_PATH = re.compile(r"[A-Za-z_][A-Za-z0-9_]*|-?\d+")
CONDITIONS = ("below", "above", "equals")


def _scalar(value: Any, place: Place) -> Any:
    if value is None or isinstance(value, Mapping | list):
        return place.error(f"'equals' of {place.entry.what} must be a number, string or boolean")
    return value


# the name, else the fact, else the value names the rule, once they are read
Naming = Titles("sensing rule '{value}'", after="value")


@dataclass(frozen=True)
class SensingRuleSpec:
    """One sensing rule, as written (see the module docstring)."""

    name: Annotated[str, Default(""), Naming]  # default: the fact or value
    topic: Annotated[str, Required(), Default(None)]
    path: Annotated[str, Key("field"), Required(), Default(None)]  # a dotted path
    fact: Annotated[str | None, Naming] = None  # a ground atom, ``(battery_low)``
    value: Annotated[str | None, Naming] = None  # a ground function, ``(battery_level)``
    below: float | None = None
    above: float | None = None
    equals: Annotated[Any, Convert(_scalar)] = None
    clear_above: float | None = None
    clear_below: float | None = None
    hold: Annotated[float, AtLeast(0.0)] = 0.0
    min_change: Annotated[float, AtLeast(0.0)] = 0.0
    line: Annotated[int, EntryLine()] = 0
    lines: Annotated[Mapping[str, int], KeyLines()] = field(
        default_factory=dict, compare=False, repr=False
    )

    def line_of(self, key: str) -> int:
        return self.lines.get(key, self.line)

    def after_read(self, entry: Entry) -> SensingRuleSpec | None:
        """The rule with its name (else its fact or value), if its parts fit together."""
        return _checked(self, entry)

    @property
    def condition(self) -> str:
        """Return the condition as written: ``level < 20 (false again above 30)``."""
        if self.below is not None:
            clear = f" (false again above {self.clear_above:g})" if self.clear_above else ""
            return f"{self.path} < {self.below:g}{clear}"
        if self.above is not None:
            clear = f" (false again below {self.clear_below:g})" if self.clear_below else ""
            return f"{self.path} > {self.above:g}{clear}"
        return f"{self.path} = {self.equals!r}"


def field_problem(path: str) -> str:
    """Say why a dotted field path is malformed, or return an empty string."""
    parts = path.split(".")
    if not path or not all(FIELD_PATH.fullmatch(p) for p in parts):
        return (
            f"field '{path}' is not a dotted path of field names and list indexes "
            "(e.g. 'level', 'pose.position.x', 'ranges.0')"
        )
    return ""


def unique_names(rules: tuple[SensingRuleSpec, ...], place: Place) -> tuple[SensingRuleSpec, ...]:
    """The rules, each name once (a rule whose name is taken is reported and left out)."""
    names: set[str] = set()
    kept: list[SensingRuleSpec] = []
    for rule in rules:
        if rule.name in names:
            place.source.error(rule.line, f"duplicate sensing rule name '{rule.name}'")
            continue
        names.add(rule.name)
        kept.append(rule)
    return tuple(kept)


def _checked(rule: SensingRuleSpec, entry: Entry) -> SensingRuleSpec | None:
    """The rule with its name, if its parts fit together (the problems reported)."""
    name = rule.name or rule.fact or rule.value or f"sensing rule at line {entry.line}"
    entry.what = f"sensing rule '{name}'"
    fact, value, path = rule.fact, rule.value, rule.path
    ok = rule.topic is not None and path is not None
    if path is not None and field_problem(path):
        entry.error("field", f"{entry.what}: {field_problem(path)}")
        ok = False
    if (fact is None) == (value is None):
        entry.error(None, f"{entry.what} needs exactly one of 'fact' and 'value'")
        ok = False
    given = [k for k in CONDITIONS if entry.has(k)]
    if entry.has("equals") and rule.equals is None:
        ok = False  # reported as it was read
    if fact is not None and len(given) != 1:
        entry.error(None, f"{entry.what}: a fact needs exactly one of {', '.join(CONDITIONS)}")
        ok = False
    if value is not None and given:
        entry.error(given[0], f"{entry.what}: a value takes no '{given[0]}'")
        ok = False
    for clear, level, goes_with, limit in (
        ("clear_above", rule.clear_above, "below", rule.below),
        ("clear_below", rule.clear_below, "above", rule.above),
    ):
        if level is None or (limit is None and entry.has(goes_with)):
            continue  # not given, or not a number (reported)
        if limit is None:
            entry.error(clear, f"{entry.what}: '{clear}' goes with '{goes_with}'")
            ok = False
        elif (level < limit) if goes_with == "below" else (level > limit):
            entry.error(
                clear,
                f"{entry.what}: '{clear}' ({level:g}) must not undo '{goes_with}' ({limit:g})",
            )
            ok = False
    if not ok or rule.topic is None:
        return None
    return dataclasses.replace(rule, name=name, topic=rule.topic.strip("/"))


def check_sensing(
    robot: RobotDescription, domain: DomainInfo, objects: Mapping[str, str], report: Report
) -> None:
    """Check that each rule names a topic the robot has, and a fact (value) of the domain's
    predicates (functions) with the right number and types of known objects."""
    published = sorted({t for c in robot.components.values() for t in c.publishes})
    ros2 = sorted(robot.ros2.topics) if robot.ros2 is not None else []
    known = {**domain.constants, **objects}
    for rule in robot.sensing:
        if rule.topic not in published and rule.topic not in ros2:
            report.error(
                rule.line_of("topic"),
                f"sensing rule '{rule.name}' reads topic '{rule.topic}', which no component "
                f"publishes and the ros2: section does not list"
                f"{did_you_mean(rule.topic, published + ros2)}",
            )
        if rule.fact is not None:
            problem = atom_problem(rule.fact, domain.predicates, known, domain, "predicate")
            if problem:
                report.error(rule.line_of("fact"), f"sensing rule '{rule.name}': {problem}")
        if rule.value is not None:
            problem = atom_problem(rule.value, domain.functions, known, domain, "function")
            if problem:
                report.error(rule.line_of("value"), f"sensing rule '{rule.name}': {problem}")


def atom_problem(
    text: str,
    signatures: Mapping[str, tuple[str, ...]],
    objects: Mapping[str, str],
    domain: DomainInfo,
    what: str,
) -> str:
    """Say why ``(name obj ...)`` is not a ground atom of the domain, or return ''."""
    words = text.strip().removeprefix("(").removesuffix(")").split()
    if not text.strip().startswith("(") or not text.strip().endswith(")") or not words:
        return f"'{text}' is not a {what} in parentheses, e.g. (battery_low)"
    name, args = words[0], words[1:]
    if name not in signatures:
        return f"unknown {what} '{name}'{did_you_mean(name, sorted(signatures))}"
    types = signatures[name]
    if len(args) != len(types):
        return (
            f"'{name}' takes {len(types)} argument{'s' * (len(types) != 1)} "
            f"({domain.signature(name)}), not {len(args)}"
        )
    for i, (arg, wanted) in enumerate(zip(args, types, strict=True)):
        if arg not in objects:
            return f"unknown object '{arg}'{did_you_mean(arg, sorted(objects))}"
        if not domain.is_a(objects[arg], wanted):
            return (
                f"argument {i + 1} of '{name}' must be a {wanted}, but '{arg}' is a {objects[arg]}"
            )
    return ""
