"""Watch the plan ahead: will the steps still to come work in the world as it is now?

When facts change outside the plan (``dura state set``, a component, a sensing rule),
the plan executor runs the rest of its plan forward from the current facts, in the
order the planner timed it: each step not yet started checks its at-start condition,
applies its at-start effects and checks its over-all condition; each step not yet
ended checks its over-all and at-end conditions and applies its at-end effects; at the end, the plan's open goals
must hold. The first condition that fails and names a fact that changed is a road
blocked ahead: the executor asks for a new plan now, not when the robot gets there.
A failure that names no changed fact is left to the executor as the plan runs (the
simulation follows the planner's timing, which the real run need not keep), and a
change that breaks nothing changes nothing.
"""

from __future__ import annotations

from collections.abc import Collection, Iterable, Sequence
from dataclasses import dataclass

from executive.planning.expression import Expression, WorldState, atoms
from executive.planning.partial_order import Effect, Step, apply
from executive.planning.step_run import StepRun, StepState
from knowledge.records import Fact

Key = tuple[str, tuple[str, ...]]


@dataclass(frozen=True)
class Ahead:
    """A step still to come, and whether it has started (its at-start part is done)."""

    step: Step
    started: bool


@dataclass(frozen=True)
class Blocked:
    """What fails ahead: a step's condition (or a goal, ``step`` None) and the changed
    facts it names."""

    step: Step | None
    part: str  # at-start, over-all, at-end, goal
    condition: Expression
    changed: tuple[Key, ...]

    def __str__(self) -> str:
        facts = ", ".join("(" + " ".join((n, *a)) + ")" for n, a in self.changed)
        where = f"step {self.step.label} ahead" if self.step is not None else "the plan's goal"
        return f"{where}: {self.part} condition {self.condition} will not hold ({facts} changed)"


def steps_ahead(runs: Iterable[StepRun]) -> list[Ahead]:
    """Return the steps of a plan run still to come: pending, or dispatched and not ended."""
    return [
        Ahead(r.step, r.started) for r in runs if r.state is StepState.PENDING or r.state.active
    ]


def look_ahead(
    steps: Sequence[Ahead],
    facts: Iterable[Fact],
    changed: Collection[Key],
    goals: Sequence[Expression] = (),
) -> Blocked | None:
    """Return the first condition ahead that fails and names a changed fact (see the
    module docstring); ``None`` if the rest of the plan still works."""
    if not changed:
        return None
    touched = set(changed)
    values: dict[Key, bool | float] = {(f.name, f.args): f.value for f in facts}
    moments: list[tuple[float, int, int, Ahead]] = []
    for n, ahead in enumerate(steps):
        step = ahead.step
        if not ahead.started:
            moments.append((step.start, 1, n, ahead))
        # at one instant, ends come before starts (one step frees what the next needs);
        # an instantaneous step ends right after it starts
        moments.append((step.start + (step.duration or 0.0), 0 if step.duration else 2, n, ahead))
    for _, end, _, ahead in sorted(moments, key=lambda m: m[:3]):
        step = ahead.step
        if end == 1:  # its start: the at-start condition, then over all from just after
            before: tuple[tuple[str, Expression], ...] = (("at-start", step.at_start),)
            effects: tuple[Effect, ...] = step.start_effects
            after: tuple[tuple[str, Expression], ...] = (("over-all", step.over_all),)
        else:
            before = (("over-all", step.over_all), ("at-end", step.at_end))
            effects, after = step.end_effects, ()
        blocked = _checks(step, before, values, touched)
        if blocked is not None:
            return blocked
        state = _state(values)
        add, remove = apply(effects, state)
        for f in remove:
            values.pop((f.name, f.args), None)
        for f in add:
            values[(f.name, f.args)] = f.value
        blocked = _checks(step, after, values, touched)
        if blocked is not None:
            return blocked
    state = _state(values)
    for goal in goals:
        blocked = _check(None, "goal", goal, state, touched)
        if blocked is not None:
            return blocked
    return None


def _checks(
    step: Step,
    checks: tuple[tuple[str, Expression], ...],
    values: dict[Key, bool | float],
    touched: set[Key],
) -> Blocked | None:
    state = _state(values)
    for part, condition in checks:
        blocked = _check(step, part, condition, state, touched)
        if blocked is not None:
            return blocked
    return None


def _state(values: dict[Key, bool | float]) -> WorldState:
    return WorldState(Fact(n, a, v) for (n, a), v in values.items())


def _check(
    step: Step | None, part: str, condition: Expression, state: WorldState, touched: set[Key]
) -> Blocked | None:
    if state.holds(condition):
        return None
    named = sorted(atoms(condition) & touched)
    return Blocked(step, part, condition, tuple(named)) if named else None
