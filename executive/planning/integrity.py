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
from typing import Any

from executive.bus.clock import Clock
from executive.planning.expression import Expression, Signature, WorldState, parse
from executive.planning.goals import normalized, submit
from knowledge.description import RobotDescription
from knowledge.domain import DomainInfo
from knowledge.errors import ConfigError, DomainError
from knowledge.finding import Report
from knowledge.knowledge_base import KnowledgeBase
from knowledge.records import Goal, GoalState
from knowledge.yamlsource import Section, compose, did_you_mean, line_of


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
    rules: list[IntegrityRule] = []
    node = compose(path, report)
    signature = Signature.of(domain, objects)
    if node is not None:
        top = Section(node, "the integrity rules", report)
        names: set[str] = set()
        for item in top.sequence("goals") if top.valid else []:
            rule = _rule(item, report, robot, signature)
            if rule is None:
                continue
            if rule.name in names:
                report.error(line_of(item), f"duplicate rule name '{rule.name}'")
            names.add(rule.name)
            rules.append(rule)
        if top.valid:
            top.close()
    elif not report.findings:
        report.error(None, "is empty")
    if own and report.errors:
        raise ConfigError("\n".join(str(f) for f in report.errors))
    return rules


def _rule(
    node: Any, report: Report, robot: RobotDescription, signature: Signature
) -> IntegrityRule | None:
    s = Section(node, "integrity rule", report)
    if not s.valid:
        return None
    name = s.text("name", required=True)
    if name is not None:
        s.what = f"integrity rule '{name}'"
    goal = s.text("goal", required=True)
    priority = s.integer("priority", 0)
    deadline_node = s.has("deadline")
    deadline = s.number("deadline", 0.0, minimum=0.001) if deadline_node else None
    hold = s.number("for", 0.0, minimum=0.0)
    keep = s.flag("keep", False)
    when = s.section("when", required=True)
    s.close()
    where = f"{report.path}:{s.line}"
    trigger: Trigger | None = None
    subject = None
    if when is not None and when.valid:
        written = when.written()
        for key in written:
            if key in TRIGGERS:
                subject = when.text(key, required=True)
                trigger = Trigger(key) if subject is not None else None
        if len([k for k in written if k in TRIGGERS]) != 1:
            report.error(
                when.line, f"'when' of {s.what} needs exactly one of {', '.join(TRIGGERS)}"
            )
            trigger = None
        when.close()
    if goal is not None:
        try:
            parse(goal, signature)
        except DomainError as e:
            report.error(s.key_line("goal"), f"{s.what}: {e}")
            goal = None
    trigger_line = when.key_line(trigger.value) if when is not None and trigger else s.line
    if trigger in (Trigger.PERMANENT_FAULT, Trigger.DIAGNOSIS) and subject not in robot.components:
        report.error(
            trigger_line,
            f"{s.what} names unknown component '{subject}'"
            f"{did_you_mean(str(subject), sorted(robot.components))}",
        )
        trigger = None
    if trigger is Trigger.CONDITION and subject is not None:
        try:
            parse(subject, signature, "condition")
        except DomainError as e:
            report.error(trigger_line, f"{s.what}: {e}")
            trigger = None
    if name is None or goal is None or trigger is None or subject is None:
        return None
    return IntegrityRule(
        name, trigger, subject, normalized(goal), priority, deadline, hold, where, keep
    )


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
        watched = [g for g in self.kb.goals([GoalState.ACHIEVED]) if g.keep]
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
