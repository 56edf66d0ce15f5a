"""The rule engine: which repair rules fire, given the newest observations and diagnoses.

Python keeps what changes over time: a window of the newest observations of every
observer a rule mentions, a window of the newest diagnoses, when each rule fired and
whether a single-shot rule is spent. Each evaluation turns that state into facts and
lets ``rules.lp`` (with the user's ASP files) decide which rules fire; several can
fire at once, highest priority first.

A rule fires when its condition becomes true; with ``recall_duration`` it fires again
while the condition holds, at most once per ``recall_duration`` seconds (a condition
that comes back sooner after a firing waits until the time is up).
"""

from __future__ import annotations

import time
from collections import deque
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path

from executive.bus.payloads import DiagnosisInfo, ObservationInfo
from knowledge.asp import Answer, Asp, atom, facts
from knowledge.errors import ConfigError
from monitoring.repair.action import Firing
from monitoring.repair.rule import (
    FaultCondition,
    ObservationCondition,
    Rule,
    RuleSet,
    observation_key,
)

PROGRAM = Path(__file__).with_name("rules.lp")

Key = tuple[str, tuple[str, ...]]


def _resource(resources: tuple[str, ...]) -> object:
    return resources[0] if len(resources) == 1 else resources


@dataclass(frozen=True)
class Fired:
    """A rule that fired, and why."""

    rule: Rule
    firing: Firing


class RuleEngine:
    """Evaluates rules against the newest observations and diagnoses.

    Raises:
        ConfigError: two rules share a name.
        AspError: an ASP file of the rules is invalid (``file:line: reason``).
    """

    def __init__(
        self, rule_sets: Sequence[RuleSet], *, clock: Callable[[], float] = time.monotonic
    ) -> None:
        self.rules: tuple[Rule, ...] = tuple(r for s in rule_sets for r in s.rules)
        self.asp_files: tuple[Path, ...] = tuple(p for s in rule_sets for p in s.asp)
        self._clock = clock
        names = [r.name for r in self.rules]
        for name in names:
            if names.count(name) > 1:
                raise ConfigError(f"rule '{name}' is defined in more than one rules file")
        self._conditions: list[ObservationCondition | FaultCondition] = []
        windows: dict[Key, int] = {}
        for rule in self.rules:
            for c in (*rule.positive_observations, *rule.negative_observations):
                windows[c.key] = max(windows.get(c.key, 1), c.window)
        faults = max(
            [c.window for r in self.rules for c in (*r.positive_faults, *r.negative_faults)] or [1]
        )
        self._observations: dict[Key, deque[ObservationInfo]] = {
            key: deque(maxlen=size) for key, size in windows.items()
        }
        self._newest: dict[Key, ObservationInfo] = {}
        self._diagnoses: deque[DiagnosisInfo] = deque(maxlen=faults)
        self._fired_at: dict[str, float] = {}
        self._spent: set[str] = set()
        self._triggered: set[str] = set()
        self._last: tuple[str, Answer] | None = None  # the last program and its answer
        self._evaluate(self._rule_facts([]))  # reject invalid ASP files now

    # --- input --------------------------------------------------------------------------

    def observe(self, info: ObservationInfo) -> None:
        """Take in an observation (of any observer; unknown types are ignored)."""
        key = observation_key(info)
        if key is None:
            return
        self._newest[key] = info
        window = self._observations.get(key)
        if window is not None:
            window.append(info)

    def diagnosed(self, info: DiagnosisInfo) -> None:
        """Take in a diagnosis result."""
        self._diagnoses.append(info)

    # --- evaluation ---------------------------------------------------------------------

    def evaluate(self) -> list[Fired]:
        """The rules that fire now, highest priority first; they count as fired."""
        now = self._clock()
        ready = [r.name for r in self.rules if self._ready(r, now)]
        program = self._rule_facts(ready) + self._state_facts()
        answer = self._evaluate(program)
        self._triggered = {str(t[0]) for t in answer.get("trigger")}
        by_name = {r.name: r for r in self.rules}
        chosen = [by_name[str(name)] for name, _ in answer.get("fire") if str(name) in by_name]
        chosen.sort(key=lambda r: (-r.priority, self.rules.index(r)))
        firing = self._firing()
        for rule in chosen:
            self._fired_at[rule.name] = now
            if rule.single_shot:
                self._spent.add(rule.name)
        return [
            Fired(rule, Firing(rule.name, firing.faulty, firing.failed, time.time()))
            for rule in chosen
        ]

    def _ready(self, rule: Rule, now: float) -> bool:
        if rule.name in self._spent:
            return False
        if rule.recall_duration is None:
            return rule.name not in self._triggered  # fire when the condition becomes true
        last = self._fired_at.get(rule.name)
        return last is None or now - last >= rule.recall_duration

    def _evaluate(self, program: str) -> Answer:
        # The answer is a function of the program: most evaluations repeat the last one
        # (the newest observations did not change), so clingo runs only on a change.
        if self._last is not None and self._last[0] == program:
            return self._last[1]
        asp = Asp()
        asp.load(PROGRAM)
        for path in self.asp_files:
            asp.load(path)
        asp.add(program, source="<rules>")
        asp.ground()
        outcome = asp.solve()
        if not outcome.answers:  # only a user's ASP rule can make the program fail
            raise ConfigError(
                f"the ASP rules of {', '.join(map(str, self.asp_files))} have no answer set"
            )
        self._last = (program, outcome.answers[-1])
        return outcome.answers[-1]

    def _rule_facts(self, ready: list[str]) -> str:
        out = []
        number = 0
        for rule in self.rules:
            out.append(atom("rule", rule.name, rule.priority))
            if rule.has_condition:
                out.append(atom("conditional", rule.name))
            signed: list[tuple[str, tuple[ObservationCondition | FaultCondition, ...]]] = [
                ("positive", (*rule.positive_observations, *rule.positive_faults)),
                ("negative", (*rule.negative_observations, *rule.negative_faults)),
            ]
            for sign, conditions in signed:
                for condition in conditions:
                    out.append(atom(sign, rule.name, number))
                    count, known = self._count(condition)
                    if count >= condition.occurrences:
                        out.append(atom("holds", number))
                    if known:
                        out.append(atom("known", number))
                    number += 1
        out += [atom("ready", name) for name in ready]
        return facts(out)

    def _count(self, condition: ObservationCondition | FaultCondition) -> tuple[int, bool]:
        """How often a condition matched in its window, and whether its window has anything."""
        if isinstance(condition, ObservationCondition):
            window = list(self._observations.get(condition.key, ()))[-condition.window :]
            return sum(condition.matches(i) for i in window), bool(window)
        recent = list(self._diagnoses)[-condition.window :]
        hits = sum(any(r in d.possibly_faulty for r in condition.resources) for d in recent)
        return hits, bool(recent)

    def _state_facts(self) -> str:
        out = []
        for (kind, resources), info in self._newest.items():
            resource = _resource(resources)
            out.append(atom("observation", kind, resource, info.observation))
            if info.failed:
                out.append(atom("failed", kind, resource))
        if self._diagnoses:
            newest = self._diagnoses[-1]
            out.append(atom("status", newest.status))
            for i, diagnosis in enumerate(newest.diagnoses):
                out += [atom("diagnosis", i, name) for name in diagnosis]
            out += [atom("possibly_faulty", name) for name in sorted(newest.possibly_faulty)]
        return facts(out)

    def _firing(self) -> Firing:
        faulty = tuple(sorted(self._diagnoses[-1].possibly_faulty)) if self._diagnoses else ()
        failed = tuple(
            f"{kind}[{', '.join(resources)}]"
            for (kind, resources), info in self._newest.items()
            if info.failed
        )
        return Firing("", faulty, failed)
