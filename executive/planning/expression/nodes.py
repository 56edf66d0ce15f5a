"""The expression tree: ground PDDL conditions and numeric expressions as frozen nodes.

Goals, the conditions of plan steps and the conditions of integrity rules are all
ground expressions: a small tree of frozen nodes with no unified-planning objects in
it, so the plan executor and the CLI evaluate them without loading a planner.
"""

from __future__ import annotations

import operator
from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass
from typing import Union


@dataclass(frozen=True)
class Const:
    """A truth value or a number."""

    value: bool | float

    def __str__(self) -> str:
        if isinstance(self.value, bool):
            return "(and)" if self.value else "(or)"
        return f"{self.value:g}"


@dataclass(frozen=True)
class Atom:
    """A ground predicate: true when the knowledge base holds the fact."""

    name: str
    args: tuple[str, ...] = ()

    def __str__(self) -> str:
        return "(" + " ".join((self.name, *self.args)) + ")"


@dataclass(frozen=True)
class Value:
    """A ground numeric function: the number the knowledge base holds for it."""

    name: str
    args: tuple[str, ...] = ()

    def __str__(self) -> str:
        return "(" + " ".join((self.name, *self.args)) + ")"


@dataclass(frozen=True)
class Not:
    arg: Expression

    def __str__(self) -> str:
        return f"(not {self.arg})"


@dataclass(frozen=True)
class And:
    args: tuple[Expression, ...]

    def __str__(self) -> str:
        return "(and" + "".join(f" {a}" for a in self.args) + ")"


@dataclass(frozen=True)
class Or:
    args: tuple[Expression, ...]

    def __str__(self) -> str:
        return "(or" + "".join(f" {a}" for a in self.args) + ")"


@dataclass(frozen=True)
class Compare:
    """A numeric comparison: ``op`` is one of ``< <= > >= =``."""

    op: str
    left: Expression
    right: Expression

    def __str__(self) -> str:
        return f"({self.op} {self.left} {self.right})"


@dataclass(frozen=True)
class Arith:
    """Numeric arithmetic: ``op`` is one of ``+ - * /``; ``(- x)`` negates."""

    op: str
    args: tuple[Expression, ...]

    def __str__(self) -> str:
        return f"({self.op}" + "".join(f" {a}" for a in self.args) + ")"


Expression = Union[Const, Atom, Value, Not, And, Or, Compare, Arith]  # noqa: UP007 (runtime alias)

TRUE = Const(True)
FALSE = Const(False)

COMPARISONS: Mapping[str, Callable[[float, float], bool]] = {
    "<": operator.lt,
    "<=": operator.le,
    ">": operator.gt,
    ">=": operator.ge,
    "=": operator.eq,
}


def conjunction(parts: Iterable[Expression]) -> Expression:
    """The conjunction of parts, flattened; ``TRUE`` for none."""
    flat: list[Expression] = []
    for p in parts:
        if isinstance(p, And):
            flat.extend(p.args)
        elif p != TRUE:
            flat.append(p)
    if not flat:
        return TRUE
    return flat[0] if len(flat) == 1 else And(tuple(flat))


def atoms(expression: Expression) -> frozenset[tuple[str, tuple[str, ...]]]:
    """The ground atoms and functions an expression mentions, as (name, args)."""
    found: set[tuple[str, tuple[str, ...]]] = set()

    def walk(e: Expression) -> None:
        if isinstance(e, (Atom, Value)):
            found.add((e.name, e.args))
        elif isinstance(e, Not):
            walk(e.arg)
        elif isinstance(e, (And, Or, Arith)):
            for a in e.args:
                walk(a)
        elif isinstance(e, Compare):
            walk(e.left)
            walk(e.right)

    walk(expression)
    return frozenset(found)
