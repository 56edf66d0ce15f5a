"""Scheduling problems for tests and benchmarks: the thesis use case and generated robots."""

from __future__ import annotations

import functools
import random
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

from executive.tasks.schedule import Request
from knowledge.description import BehaviorSpec, FunctionalitySpec, RobotDescription
from knowledge.robot import load_robot
from tests.conftest import USECASE


@dataclass(frozen=True)
class Problem:
    functionalities: tuple[FunctionalitySpec, ...]
    requests: tuple[Request, ...]
    faulty: frozenset[str] = field(default_factory=frozenset)


@functools.cache
def usecase_robot() -> RobotDescription:
    """The thesis use-case robot (read once: it is frozen)."""
    return load_robot(USECASE)


def usecase() -> tuple[dict[str, FunctionalitySpec], dict[str, BehaviorSpec]]:
    """The thesis use case's functionalities and behaviors, by name."""
    robot = usecase_robot()
    return dict(robot.functionalities), dict(robot.behaviors)


def request(
    behavior: BehaviorSpec, request_id: str, duration: float = 10.0, **constraints: Any
) -> Request:
    """A request for a behavior's capabilities."""
    return Request(request_id, behavior.name, behavior.requires, duration, **constraints)


def functionality(
    name: str,
    provides: Sequence[str],
    requires: Sequence[str] = (),
    *,
    shareable: bool = True,
    rating: float = 1.0,
) -> FunctionalitySpec:
    return FunctionalitySpec(
        name=name,
        command=(),
        provides=tuple(provides),
        requires=tuple(requires),
        shareable=shareable,
        rating=rating,
    )


def generate(size: int, seed: int) -> Problem:
    """A random robot and ``size`` requests: a quarter running, some with deadlines.

    The robot has about ``size / 2`` capabilities (at least 6) with one to three
    providers each; a provider may require a capability of a lower index, a quarter
    are not shareable, and one functionality is permanently faulty. Running requests
    have valid configurations that do not conflict with each other.
    """
    rng = random.Random(seed)
    capabilities = [f"c{i}" for i in range(max(6, size // 2))]
    functionalities: list[FunctionalitySpec] = []
    for i, capability in enumerate(capabilities):
        for j in range(rng.randint(1, 3)):
            requires = (rng.choice(capabilities[:i]),) if i and rng.random() < 0.4 else ()
            functionalities.append(
                functionality(
                    f"f{i}_{j}",
                    [capability],
                    requires,
                    shareable=rng.random() < 0.75,
                    rating=rng.randint(1, 10),
                )
            )
    faulty = frozenset({rng.choice(functionalities).name})
    behaviors = {
        f"b{k}": tuple(rng.sample(capabilities, rng.randint(1, 3)))
        for k in range(max(4, size // 4))
    }
    requests: list[Request] = []
    held: set[str] = set()
    by_name = {f.name: f for f in functionalities}
    for k in range(size):
        name = rng.choice(sorted(behaviors))
        needs = behaviors[name]
        duration = float(rng.randint(5, 60))
        configuration = (
            _configuration(needs, functionalities, faulty, held | {name})
            if rng.random() < 0.25 and name not in held
            else None
        )
        if configuration is not None:
            held |= {name} | {f for f in configuration.values() if not by_name[f].shareable}
            requests.append(
                Request(f"r{k}", name, needs, duration, running=True, configuration=configuration)
            )
            continue
        earliest = float(rng.choice([0, 0, rng.randint(1, 30)]))
        deadline = earliest + duration + rng.randint(10, 120) if rng.random() < 0.3 else None
        requests.append(Request(f"r{k}", name, needs, duration, earliest, deadline))
    # a few pairs of waiting requests start together
    waiting = [r for r in requests if not r.running and r.deadline is None]
    pairs = rng.sample(waiting, len(waiting) // 10 * 2) if len(waiting) >= 10 else []
    partners = {}
    for a, b in zip(pairs[::2], pairs[1::2], strict=True):
        partners[a.id], partners[b.id] = b.id, a.id
    requests = [
        Request(r.id, r.behavior, r.needs, r.duration, r.earliest, r.deadline, (partners[r.id],))
        if r.id in partners
        else r
        for r in requests
    ]
    return Problem(tuple(functionalities), tuple(requests), faulty)


def _configuration(
    needs: Sequence[str],
    functionalities: Sequence[FunctionalitySpec],
    faulty: frozenset[str],
    held: set[str],
) -> Mapping[str, str] | None:
    """The best-rated providers, closed under requires, avoiding held and faulty ones."""
    chosen: dict[str, str] = {}
    todo = list(needs)
    while todo:
        capability = todo.pop()
        if capability in chosen:
            continue
        options = sorted(
            (
                f
                for f in functionalities
                if capability in f.provides and f.name not in faulty and f.name not in held
            ),
            key=lambda f: -f.rating,
        )
        if not options:
            return None
        chosen[capability] = options[0].name
        todo += options[0].requires
    return chosen
