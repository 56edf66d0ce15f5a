"""The integrity goal generator (thesis 5.1.2, Figure 5.4): goals that keep the robot
going, posted by rules when conditions hold.

Rules live in YAML files named under ``integrity:`` in the robot description::

    goals:
      - name: report_lidar                 # unique, for the event log
        when: {permanent_fault: lidar}     # exactly one trigger, see below
        goal: (reported lidar)             # a PDDL goal expression
        priority: 10                       # optional (default 0)
        deadline: 60                       # optional, seconds from posting
        for: 2                             # optional: the trigger must hold this long
        keep: true                         # optional: a maintenance goal (re-posted
                                           # whenever it stops holding)

Triggers: ``permanent_fault: COMPONENT`` (the KB marks it permanently faulty),
``diagnosis: COMPONENT`` (it is in every current diagnosis, i.e. certainly faulty),
``condition: PDDL`` (a condition over the KB facts and numeric values, e.g.
``(< (battery_level robot) 20)``). A rule fires when its trigger becomes true (and has
stayed true for ``for`` seconds), posts its goal unless the same goal is already
open (or, for a maintenance goal, achieved and watched), and fires again only after
the trigger was false once.
"""

from __future__ import annotations

import enum
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Annotated, Any, NamedTuple

from executive.bus.clock import Clock
from executive.planning.expression import (
    Expression,
    Signature,
    WorldState,
    check_syntax,
    parse,
)
from executive.planning.goals import normalized, submit
from knowledge.conventions import (
    AtLeast,
    Convert,
    Default,
    EntryLine,
    Key,
    Label,
    Required,
    Titles,
)
from knowledge.description import RobotDescription
from knowledge.domain import DomainInfo
from knowledge.errors import ConfigError, DomainError, did_you_mean
from knowledge.finding import Report
from knowledge.knowledge_base import KnowledgeBase
from knowledge.records import Goal
from knowledge.typed_reader import Entry, Place, read, read_value
from knowledge.yamlsource import DocumentSource, read_file


class Trigger(enum.Enum):
    """What makes a rule fire (the key under ``when:``)."""

    PERMANENT_FAULT = "permanent_fault"  # the subject is a component
    DIAGNOSIS = "diagnosis"  # the subject is a component
    CONDITION = "condition"  # the subject is a PDDL condition


TRIGGERS = tuple(t.value for t in Trigger)


@dataclass(frozen=True)
class IntegrityRule:
    """One rule: when ``trigger`` on ``subject`` holds for ``hold`` seconds, post ``goal``."""

    name: str
    trigger: Trigger
    subject: str  # a component name, or a PDDL condition
    goal: str
    priority: int = 0
    deadline: float | None = None
    hold: float = 0.0
    where: str = ""  # file:line, for messages
    keep: bool = False  # post a maintenance goal


class _Context(NamedTuple):
    """What the rules of a file are checked against, and the names of those read;
    without a robot and its signature (a file checked alone), only what needs neither."""

    robot: RobotDescription | None
    signature: Signature | None
    path: str
    names: set[str]

    def check(self, text: str, what: str) -> None:
        """Raise DomainError if ``text`` is no condition of the domain (alone: of PDDL)."""
        if self.signature is None:
            check_syntax(text, what)
        else:
            parse(text, self.signature, what)


@dataclass(frozen=True)
class When:
    """What makes a rule fire, as written: exactly one trigger and its subject."""

    permanent_fault: str | None = None
    diagnosis: str | None = None
    condition: str | None = None

    def after_read(self, entry: Entry) -> When | None:
        if len([k for k in entry.written if k in TRIGGERS]) != 1:
            entry.error(None, f"{entry.what} needs exactly one of {', '.join(TRIGGERS)}")
            return None
        return self

    @property
    def trigger(self) -> tuple[Trigger, str] | None:
        """The trigger given and its subject."""
        for trigger in Trigger:
            subject = getattr(self, trigger.value)
            if subject is not None:
                return trigger, subject
        return None


@dataclass(frozen=True)
class RuleEntry:
    """An integrity rule as written (see the module docstring)."""

    name: Annotated[str, Titles("integrity rule '{value}'"), Required(), Default(None)]
    goal: Annotated[str, Required(), Default(None)]
    priority: int = 0
    deadline: Annotated[float | None, AtLeast(0.001)] = None
    hold: Annotated[float, Key("for"), AtLeast(0.0)] = 0.0
    keep: bool = False
    when: Annotated[When | None, Required()] = None
    line: Annotated[int, EntryLine()] = 0

    def after_read(self, entry: Entry) -> IntegrityRule | None:
        """The rule, if its goal and trigger fit the robot and its domain."""
        context: _Context = entry.source.context
        goal: str | None = self.goal
        if goal is not None:
            try:
                context.check(goal, "goal")
            except DomainError as e:
                entry.error("goal", f"{entry.what}: {e}")
                goal = None
        found = self.when.trigger if self.when is not None else None
        trigger, subject = found if found is not None else (None, None)
        line = self.line
        if trigger is not None:
            line = entry.source.key_line((*entry.path, "when", trigger.value)) or line
        components = () if context.robot is None else context.robot.components
        named = trigger in (Trigger.PERMANENT_FAULT, Trigger.DIAGNOSIS)
        if named and context.robot is not None and subject not in components:
            entry.source.error(
                line,
                f"{entry.what} names unknown component '{subject}'"
                f"{did_you_mean(str(subject), sorted(components))}",
            )
            trigger = None
        if trigger is Trigger.CONDITION and subject is not None:
            try:
                context.check(subject, "condition")
            except DomainError as e:
                entry.source.error(line, f"{entry.what}: {e}")
                trigger = None
        if self.name is None or goal is None or trigger is None or subject is None:
            return None
        if self.name in context.names:
            entry.error(None, f"duplicate rule name '{self.name}'")  # kept, as the first
        context.names.add(self.name)
        return IntegrityRule(
            self.name, trigger, subject, normalized(goal), self.priority, self.deadline,
            self.hold, f"{context.path}:{self.line}", self.keep,
        )  # fmt: skip


def _rule(value: Any, place: Place) -> Any:
    return read_value(RuleEntry, value, place)  # an IntegrityRule, by its after_read


@dataclass(frozen=True)
class IntegrityFile:
    """A file of integrity rules, as written."""

    goals: Annotated[
        tuple[Annotated[IntegrityRule, Convert(_rule)], ...], Label("integrity rule")
    ] = ()


def read_rules(
    path: Path,
    robot: RobotDescription,
    domain: DomainInfo,
    objects: Mapping[str, str],
    report: Report | None = None,
) -> list[IntegrityRule]:
    """Read one rules file, checked against the robot, its domain and the objects.

    Every problem goes to ``report`` if one is given.

    Raises:
        ConfigError: every problem, one per line, as ``file:line: message`` (only when
            no report is given).
    """
    own = report is None
    report = report or Report(str(path))
    rules = _read(path, report, robot, Signature.of(domain, objects))
    if own and report.errors:
        raise ConfigError("\n".join(str(f) for f in report.errors))
    return rules


def check_rules_alone(path: Path, report: Report) -> None:
    """Check a rules file that no robot names, in the words of :func:`read_rules`: what
    needs neither the robot nor its domain (keys and values, one trigger per rule, unique
    names, the form of each goal and condition); not the components and the names in
    the expressions."""
    _read(path, report, None, None)


def _read(
    path: Path, report: Report, robot: RobotDescription | None, signature: Signature | None
) -> list[IntegrityRule]:
    found = read_file(path, report)
    if found is None:
        if not report.findings:
            report.error(None, "is empty")
        return []
    source = DocumentSource(found, report, context=_Context(robot, signature, report.path, set()))
    written = read(IntegrityFile, found.value, source, "the integrity rules")
    return list(written.goals) if written is not None else []


@dataclass
class _Watch:
    since: float | None = None  # when the trigger became true
    fired: bool = False  # fired since it became true


@dataclass
class IntegrityGoals:
    """Evaluates rules against the KB and the latest diagnoses; posts goals.

    Call :meth:`check` whenever something a rule reads may have changed (diagnoses,
    faults, facts) and again at :meth:`next_check`, for rules that wait ``for`` a while.
    Times are the clock's robot seconds (``for`` is robot time).
    """

    kb: KnowledgeBase
    domain: DomainInfo
    rules: Sequence[IntegrityRule]
    diagnoses: tuple[frozenset[str], ...] = ()
    clock: Clock = field(default_factory=Clock)
    _watch: dict[str, _Watch] = field(default_factory=dict)

    def diagnosed(self, payload: Mapping[str, Any]) -> None:
        """Take a ``diagnoses`` bus payload: {"status", "diagnoses": [[names]], "stamp"}."""
        found = payload.get("diagnoses") or []
        self.diagnoses = tuple(frozenset(str(n) for n in d) for d in found if isinstance(d, list))

    def _holds(self, rule: IntegrityRule, state: WorldState, faulty: set[str]) -> bool:
        if rule.trigger is Trigger.PERMANENT_FAULT:
            return rule.subject in faulty
        if rule.trigger is Trigger.DIAGNOSIS:
            return bool(self.diagnoses) and all(rule.subject in d for d in self.diagnoses)
        try:
            condition: Expression = parse(
                rule.subject, Signature.of(self.domain, self.kb.objects())
            )
        except DomainError:
            return False  # an object it names is gone
        return state.holds(condition)

    def check(self, now: float | None = None) -> list[Goal]:
        """Post the goals of the rules that fire now; returns them."""
        now = self.clock.monotonic() if now is None else now
        state = WorldState(self.kb.facts())
        faulty = {c.name for c in self.kb.components() if c.permanent_fault}
        watched = self.kb.kept_goals()
        open_goals = {g.expression for g in (*self.kb.open_goals(), *watched)}
        posted: list[Goal] = []
        for rule in self.rules:
            watch = self._watch.setdefault(rule.name, _Watch())
            if not self._holds(rule, state, faulty):
                self._watch[rule.name] = _Watch()
                continue
            if watch.since is None:
                watch.since = now
            if watch.fired or now - watch.since < rule.hold:
                continue
            watch.fired = True
            if rule.goal in open_goals:
                continue
            try:
                goal = submit(self.kb, self.domain, rule.goal, priority=rule.priority,
                              deadline=rule.deadline, source="integrity",
                              keep=rule.keep)  # fmt: skip
            except DomainError as e:
                self.kb.log_event("INTEGRITY_REFUSED", rule.name, {"reason": str(e)})
                continue
            self.kb.log_event(
                "INTEGRITY_GOAL", rule.name, {"goal": goal.id, "trigger": rule.trigger.value}
            )
            open_goals.add(rule.goal)
            posted.append(goal)
        return posted

    def next_check(self) -> float | None:
        """When a rule waiting ``for`` its trigger to persist is due (the clock's
        :meth:`~executive.bus.clock.Clock.monotonic` seconds)."""
        due = [
            w.since + r.hold
            for r in self.rules
            if (w := self._watch.get(r.name)) is not None and w.since is not None and not w.fired
        ]
        return min(due, default=None)
