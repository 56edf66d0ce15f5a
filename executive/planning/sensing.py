"""Sensing: the robot's world kept in step with its topics, by the rules of the robot
description's ``sensing:`` section (:mod:`knowledge.sensing_spec`).

Each rule watches one field of one topic (dura's bus, or a ROS 2 topic through the
topic source that serves it, as the observers read it) and sets or unsets a fact, or
writes a numeric value, in the knowledge base. A fact follows its condition with
hysteresis: ``below: 20, clear_above: 30`` makes ``(battery_low)`` true under 20 and
false again only above 30. A new verdict counts once it has lasted ``hold`` seconds of
robot time, so a noisy value does not flap; a value is written when it moved by at
least ``min_change`` (and at most once per ``hold`` seconds). Each change is one
transaction with a ``STATE_SET`` or ``STATE_UNSET`` event whose data names the rule
(``{"source": "sensing", "rule": ..., "topic": ..., "value": ...}``), and goes where a
user's ``dura state set`` goes: the plan executor, the goal planner and the integrity
goals.

All rule state lives on one worker thread; bus and ROS 2 handlers only post to it.
"""

from __future__ import annotations

import logging
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

from executive.bus.clock import Clock
from executive.bus.keys import topic as topic_key
from executive.bus.message import Message
from executive.bus.timers import Timer
from executive.bus.topic_source import Subscription
from executive.bus.worker import Worker
from executive.planning.expression import Signature, parse_fact
from knowledge.domain import DomainInfo
from knowledge.errors import DuraError
from knowledge.knowledge_base import KnowledgeBase
from knowledge.records import Fact
from knowledge.sensing_spec import SensingRuleSpec

log = logging.getLogger("dura.sensing")

Subscribe = Callable[[str, Callable[[Message], None]], Subscription]
Changed = Callable[[list[Fact], str], None]  # the facts changed, and the reason


def read_field(payload: Mapping[str, Any], path: str) -> Any:
    """Return the value at a dotted path of a message (list items by index), or ``None``."""
    value: Any = payload
    for part in path.split("."):
        if isinstance(value, Mapping):
            value = value.get(part)
        elif isinstance(value, (list, tuple)) and part.lstrip("-").isdigit():
            index = int(part)
            value = value[index] if -len(value) <= index < len(value) else None
        else:
            return None
    return value


def _number(value: Any) -> float | None:
    if isinstance(value, bool):
        return float(value)
    return float(value) if isinstance(value, (int, float)) else None


def verdict(rule: SensingRuleSpec, value: Any, current: bool | None) -> bool | None:
    """Tell whether a rule's fact holds for a field's value, given whether it holds now
    (hysteresis); ``None`` when the value does not fit the rule (not a number)."""
    if rule.below is not None or rule.above is not None:
        number = _number(value)
        if number is None:
            return None
        if rule.below is not None:
            if number < rule.below:
                return True
            clear = rule.clear_above if rule.clear_above is not None else rule.below
            return bool(current) and number <= clear
        assert rule.above is not None  # noqa: S101 (one of the two, by the guard above)
        if number > rule.above:
            return True
        clear = rule.clear_below if rule.clear_below is not None else rule.above
        return bool(current) and number >= clear
    if isinstance(rule.equals, (int, float)) and not isinstance(rule.equals, bool):
        number = _number(value)
        return None if number is None else number == float(rule.equals)
    return bool(value == rule.equals)


@dataclass
class _Rule:
    """One rule and what it last did (the sensing thread only)."""

    spec: SensingRuleSpec
    fact: Fact  # its fact (value True) or its function (value 0)
    pending: bool | None = None  # a new verdict waiting out the hold
    since: float = 0.0  # robot time it began
    value: Any = None  # the newest field value
    written: float | None = None  # robot time of the last value written
    timer: Timer | None = None


class Sensing:
    """Runs the sensing rules of a robot (see the module docstring).

    Args:
        subscribe: subscribe a handler to a topic key (the topic source serving it, or
            the bus).
        changed: told of the facts each change wrote, with the reason (on the sensing
            thread).
    """

    def __init__(
        self,
        kb: KnowledgeBase,
        domain: DomainInfo,
        rules: Sequence[SensingRuleSpec],
        *,
        subscribe: Subscribe,
        changed: Changed,
        clock: Clock,
    ) -> None:
        self.kb = kb
        self.domain = domain
        self.specs = tuple(rules)
        self.subscribe = subscribe
        self.changed = changed
        self.clock = clock
        self._worker = Worker("sensing")
        self._rules: list[_Rule] = []
        self._subscriptions: list[Subscription] = []

    def start(self) -> None:
        """Read the rules against the domain and the objects, and subscribe to their topics.

        A rule that no longer fits the objects (one was removed) is a warning naming it.
        """
        if not self.specs:
            return
        signature = Signature.of(self.domain, self.kb.objects())
        for spec in self.specs:
            text = spec.fact if spec.fact is not None else f"(= {spec.value} 0)"
            try:
                self._rules.append(_Rule(spec, parse_fact(text, signature)))
            except DuraError as e:
                log.warning("sensing rule '%s' left out: %s", spec.name, e)
        self._worker.start()
        by_topic: dict[str, list[_Rule]] = {}
        for rule in self._rules:
            by_topic.setdefault(rule.spec.topic, []).append(rule)
        for name, rules in by_topic.items():
            self._subscriptions.append(self.subscribe(topic_key(name), self._handler(rules)))

    def stop(self) -> None:
        """Stop listening and end the sensing thread."""
        for subscription in self._subscriptions:
            try:
                subscription.undeclare()
            except Exception as e:  # the bus may be closing
                log.debug("undeclare: %s", e)
        self._subscriptions = []
        self._worker.post(self._cancel_timers)
        if self._worker.running:
            self._worker.stop()

    def _handler(self, rules: list[_Rule]) -> Callable[[Message], None]:
        def heard(message: Message) -> None:
            try:
                payload = message.payload
            except DuraError as e:
                log.debug("sensing ignores a message on %s: %s", message.key, e)
                return
            values = [(rule, read_field(payload, rule.spec.path)) for rule in rules]
            self._worker.post(lambda: self._take(values))

        return heard

    # --- the sensing thread ---------------------------------------------------------------

    def _cancel_timers(self) -> None:
        for rule in self._rules:
            if rule.timer is not None:
                rule.timer.cancel()

    def _take(self, values: list[tuple[_Rule, Any]]) -> None:
        now = self.clock.monotonic()
        for rule, value in values:
            if value is None:
                continue
            rule.value = value
            try:
                if rule.spec.fact is not None:
                    self._fact(rule, now)
                else:
                    self._value(rule, now)
            except DuraError as e:
                log.warning("sensing rule '%s': %s", rule.spec.name, e)

    def _holds(self, rule: _Rule) -> bool:
        return any(f.args == rule.fact.args for f in self.kb.facts(rule.fact.name))

    def _fact(self, rule: _Rule, now: float) -> None:
        current = self._holds(rule)
        new = verdict(rule.spec, rule.value, current)
        if new is None or new == current:
            rule.pending = None
            return
        if rule.pending is not new:
            rule.pending, rule.since = new, now
        if now - rule.since < rule.spec.hold:
            self._recheck(rule, rule.since + rule.spec.hold - now)
            return
        rule.pending = None
        fact = Fact(rule.fact.name, rule.fact.args, new)
        self._write(rule, fact, "STATE_SET" if new else "STATE_UNSET")

    def _value(self, rule: _Rule, now: float) -> None:
        number = _number(rule.value)
        if number is None:
            return
        old = next(
            (f.value for f in self.kb.facts(rule.fact.name) if f.args == rule.fact.args), None
        )
        if isinstance(old, float) and abs(number - old) < max(rule.spec.min_change, 1e-12):
            return
        if rule.written is not None and now - rule.written < rule.spec.hold:
            self._recheck(rule, rule.written + rule.spec.hold - now)
            return
        rule.written = now
        self._write(rule, Fact(rule.fact.name, rule.fact.args, number), "STATE_SET")

    def _recheck(self, rule: _Rule, seconds: float) -> None:
        """Look at a rule again after ``seconds`` of robot time (no message may come)."""
        if rule.timer is not None:
            rule.timer.cancel()

        def again() -> None:
            self._take([(rule, rule.value)])

        rule.timer = self.clock.timer(seconds, lambda: self._worker.post(again))

    def _write(self, rule: _Rule, fact: Fact, kind: str) -> None:
        spec = rule.spec
        data = {"source": "sensing", "rule": spec.name, "topic": spec.topic,
                "field": spec.path, "value": rule.value}  # fmt: skip
        with self.kb.transaction():
            if fact.value is False:
                self.kb.update_facts(remove=[fact])
            else:
                self.kb.set_fact(fact)
            subject = fact if not isinstance(fact.value, bool) else Fact(fact.name, fact.args)
            self.kb.log_event(kind, str(subject), data)
        self.changed([fact], f"{fact} sensed by rule '{spec.name}' ({spec.path} = {rule.value})")
