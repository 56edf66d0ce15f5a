"""Which functionalities can still run, given the permanently faulty ones, and why not.

A permanently faulty functionality cannot run, and neither can one that requires a
capability whose every provider cannot run: it "can only run on top of" faulty ones
(thesis 7.3: once lidar is permanently faulty, so is lidar_filter). The scheduler
chooses only among usable functionalities; the fault handling reports the ones a new
permanent fault takes away. Nothing of this is stored: resetting a faulty component
after maintenance makes everything that runs on top of it usable again.
"""

from __future__ import annotations

from collections.abc import Collection, Iterable, Mapping
from dataclasses import dataclass
from functools import cached_property

from knowledge.description import FunctionalitySpec, RobotDescription


@dataclass(frozen=True)
class Availability:
    """The usable functionalities of a robot, and why each other one is not.

    Build it with :meth:`of`.
    """

    functionalities: Mapping[str, FunctionalitySpec]
    faulty: frozenset[str]
    usable: frozenset[str]

    @classmethod
    def of(
        cls, functionalities: Iterable[FunctionalitySpec], faulty: Collection[str]
    ) -> Availability:
        """Decide usability as a least fixpoint, so a cycle of requirements never runs."""
        by_name = {f.name: f for f in functionalities}
        usable: set[str] = set()
        changed = True
        while changed:
            available = {c for name in usable for c in by_name[name].provides}
            fresh = {
                f.name
                for f in by_name.values()
                if f.name not in usable
                and f.name not in faulty
                and all(c in available for c in f.requires)
            }
            usable |= fresh
            changed = bool(fresh)
        return cls(by_name, frozenset(faulty) & by_name.keys(), frozenset(usable))

    def providers(self, capability: str) -> list[FunctionalitySpec]:
        """The functionalities that provide a capability, usable or not, best rated first."""
        found = [f for f in self.functionalities.values() if capability in f.provides]
        return sorted(found, key=lambda f: (-f.rating, f.name))

    def available(self, capability: str) -> bool:
        return any(f.name in self.usable for f in self.providers(capability))

    @cached_property
    def unusable(self) -> dict[str, str]:
        """Each unusable functionality and a phrase that follows its name.

        ``"is permanently faulty"`` or ``"requires 'laser_scan' (lidar is permanently
        faulty)"``.
        """
        return {
            name: self._reason(name, ())
            for name in sorted(self.functionalities.keys() - self.usable)
        }

    def explain(self, capability: str) -> str:
        """Why a capability is unavailable, as a sentence; empty if it is available."""
        if self.available(capability):
            return ""
        return f"no provider for capability '{capability}': {self._without(capability, ())}"

    def _reason(self, name: str, seen: tuple[str, ...]) -> str:
        if name in self.faulty:
            return "is permanently faulty"
        if name in seen:
            return "requires itself"
        # not usable, not faulty: some required capability has no usable provider
        capability = next(c for c in self.functionalities[name].requires if not self.available(c))
        return f"requires '{capability}' ({self._without(capability, (*seen, name))})"

    def _without(self, capability: str, seen: tuple[str, ...]) -> str:
        providers = self.providers(capability)
        if not providers:
            return "no functionality provides it"
        return ", ".join(f"{f.name} {self._reason(f.name, seen)}" for f in providers)


def blocked_tasks(robot: RobotDescription, faulty: Collection[str]) -> dict[str, str]:
    """The tasks (PDDL actions) that cannot run, with the reason, given the permanently
    faulty components: a faulty behavior, or a capability it requires without a usable
    provider. The goal planner plans without them."""
    availability = Availability.of(robot.functionalities.values(), faulty)
    blocked: dict[str, str] = {}
    for action, task in robot.tasks.items():
        behavior = robot.behaviors[task.behavior]
        if behavior.name in faulty:
            blocked[action] = f"behavior {behavior.name} is permanently faulty"
            continue
        missing = [c for c in behavior.requires if not availability.available(c)]
        if missing:
            blocked[action] = availability.explain(missing[0])
    return blocked
