"""A robot's own facts in the fleet's world: where it is, its battery.

The fleet description maps facts of a robot's own world to facts of the fleet's
(``facts: {"(robot_at ?p)": "(at ?robot ?p)", "(battery_level)": "(battery ?robot)"}``;
``?robot`` is the robot's object). When a robot joins, and whenever its executive sets
or unsets a mapped fact (its sensing rules, its own plans, ``dura state set`` on it: the events it
publishes), the fleet reads that predicate of the robot's world again and makes the
fleet's facts of that robot follow: set what is new, unset what the robot no longer
holds, as ``dura state set`` would (the fleet's goal planner hears of it).
"""

from __future__ import annotations

import re
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass

from executive.bus.worker import Worker
from knowledge.errors import ConfigError
from knowledge.records import Fact

ROBOT = "robot"  # the variable that stands for the robot's object on the fleet's side
CHANGES = ("STATE_SET", "STATE_UNSET")
_ATOM = re.compile(r"^\(\s*([^\s()?]+)((?:\s+[^\s()]+)*)\s*\)$")
_SUBJECT = re.compile(r"^\(\s*(?:=\s*\(\s*|not\s*\(\s*)?([^\s()]+)")


@dataclass(frozen=True)
class Pattern:
    """An atom with variables (``?p``) and constants: ``(at ?robot ?p)``."""

    name: str
    args: tuple[str, ...]

    @classmethod
    def read(cls, text: str) -> Pattern:
        """Raises ConfigError: not ``(name arg ...)``."""
        found = _ATOM.match(text.strip())
        if found is None:
            raise ConfigError(f"'{text}' is not an atom such as (robot_at ?p)")
        return cls(found.group(1), tuple(found.group(2).split()))

    @property
    def variables(self) -> set[str]:
        return {a[1:] for a in self.args if a.startswith("?")}

    def match(self, args: Sequence[str], given: Mapping[str, str]) -> dict[str, str] | None:
        """The bindings under which this pattern is ``args`` (``None``: it is not)."""
        if len(args) != len(self.args):
            return None
        bound = dict(given)
        for mine, theirs in zip(self.args, args, strict=True):
            if not mine.startswith("?"):
                if mine != theirs:
                    return None
            elif bound.setdefault(mine[1:], theirs) != theirs:
                return None
        return bound

    def fill(self, bindings: Mapping[str, str]) -> tuple[str, ...]:
        return tuple(bindings[a[1:]] if a.startswith("?") else a for a in self.args)


@dataclass(frozen=True)
class FactMapping:
    """A robot's fact (``robot``) and the fleet's fact it becomes (``fleet``)."""

    robot: Pattern
    fleet: Pattern

    @classmethod
    def read(cls, robot: str, fleet: str) -> FactMapping:
        """Raises ConfigError: a side is no atom, or the fleet's side names a variable the
        robot's does not bind, or not ``?robot``."""
        mapping = cls(Pattern.read(robot), Pattern.read(fleet))
        if ROBOT not in mapping.fleet.variables:
            raise ConfigError(f"'{fleet}' does not name the robot (?{ROBOT})")
        unbound = sorted(mapping.fleet.variables - mapping.robot.variables - {ROBOT})
        if unbound:
            raise ConfigError(f"'{fleet}' names ?{unbound[0]}, which '{robot}' does not")
        return mapping

    def to_fleet(self, fact: Fact, robot: str) -> Fact | None:
        """The fleet's fact for one of the robot's (``None``: it does not match)."""
        bindings = self.robot.match(fact.args, {ROBOT: robot})
        if fact.name != self.robot.name or bindings is None:
            return None
        return Fact(self.fleet.name, self.fleet.fill(bindings), fact.value)

    def ours(self, fact: Fact, robot: str) -> bool:
        """Whether a fact of the fleet's world is one this mapping makes for ``robot``."""
        return (
            fact.name == self.fleet.name and self.fleet.match(fact.args, {ROBOT: robot}) is not None
        )


class RobotFacts:
    """Keeps the fleet's facts of one robot in step with the robot's own, on a thread of
    its own (see the module docstring).

    Args:
        mappings: the fleet's fact mappings.
        robot: the robot's object in the fleet's world.
        ask: the robot's facts of a predicate (over its bus).
        fleet_facts: the fleet's facts of a predicate.
        change: set (``unset`` false) or unset a fact of the fleet's world, by its text.
    """

    def __init__(
        self,
        mappings: Sequence[FactMapping],
        robot: str,
        *,
        ask: Callable[[str], list[Fact]],
        fleet_facts: Callable[[str], list[Fact]],
        change: Callable[[str, bool], None],
    ) -> None:
        self.mappings = list(mappings)
        self.robot = robot
        self.ask = ask
        self.fleet_facts = fleet_facts
        self.change = change
        self._worker = Worker(f"facts of {robot}")

    def start(self) -> None:
        self._worker.start()

    def stop(self) -> None:
        self._worker.stop()

    def joined(self) -> None:
        """The robot joined (again): follow every mapping."""
        for mapping in self.mappings:
            self._worker.post(lambda m=mapping: self.follow(m))  # type: ignore[misc]

    def heard(self, kind: str, subject: str) -> None:
        """An event of the robot: a change of a mapped predicate is followed."""
        found = _SUBJECT.match(subject)
        if kind not in CHANGES or found is None:
            return
        for mapping in self.mappings:
            if mapping.robot.name == found.group(1):
                self._worker.post(lambda m=mapping: self.follow(m))  # type: ignore[misc]

    def follow(self, mapping: FactMapping) -> None:
        """Make the fleet's facts of one mapping follow the robot's own."""
        translated = (mapping.to_fleet(f, self.robot) for f in self.ask(mapping.robot.name))
        wanted = {f for f in translated if f is not None}
        held = {f for f in self.fleet_facts(mapping.fleet.name) if mapping.ours(f, self.robot)}
        for fact in held - wanted:
            if isinstance(fact.value, bool) and (fact.name, fact.args) not in {
                (w.name, w.args) for w in wanted
            }:
                self.change(str(fact), True)
        for fact in wanted - held:
            self.change(str(fact), False)
