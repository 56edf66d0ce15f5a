"""Evaluating expressions over the knowledge base's facts (a closed world)."""

from __future__ import annotations

from collections.abc import Iterable

from executive.planning.expression.nodes import (
    COMPARISONS,
    And,
    Arith,
    Atom,
    Compare,
    Const,
    Expression,
    Not,
    Or,
    Value,
)
from knowledge.records import Fact


class WorldState:
    """The facts of the knowledge base, for evaluating expressions (closed world)."""

    def __init__(self, facts: Iterable[Fact] = ()) -> None:
        self._values: dict[tuple[str, tuple[str, ...]], bool | float] = {
            (f.name, f.args): f.value for f in facts if f.value is not False
        }

    def holds(self, expression: Expression) -> bool:
        """Whether a condition is true; a comparison with an unknown number is false."""
        e = expression
        if isinstance(e, Const):
            return bool(e.value)
        if isinstance(e, Atom):
            return self._values.get((e.name, e.args)) is True
        if isinstance(e, Not):
            return not self.holds(e.arg)
        if isinstance(e, And):
            return all(self.holds(a) for a in e.args)
        if isinstance(e, Or):
            return any(self.holds(a) for a in e.args)
        if isinstance(e, Compare):
            left, right = self.number(e.left), self.number(e.right)
            return left is not None and right is not None and COMPARISONS[e.op](left, right)
        raise TypeError(f"{e} is a number, not a condition")

    def number(self, expression: Expression) -> float | None:
        """The value of a numeric expression; ``None`` if a function has no value."""
        e = expression
        if isinstance(e, Const) and not isinstance(e.value, bool):
            return float(e.value)
        if isinstance(e, Value):
            v = self._values.get((e.name, e.args))
            return None if v is None or isinstance(v, bool) else float(v)
        if isinstance(e, Arith):
            values = [self.number(a) for a in e.args]
            if any(v is None for v in values):
                return None
            nums = [v for v in values if v is not None]
            if e.op == "-" and len(nums) == 1:
                return -nums[0]
            result = nums[0]
            for v in nums[1:]:
                if e.op == "+":
                    result += v
                elif e.op == "-":
                    result -= v
                elif e.op == "*":
                    result *= v
                elif v == 0:
                    return None
                else:
                    result /= v
            return result
        raise TypeError(f"{e} is a condition, not a number")
