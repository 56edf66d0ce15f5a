"""Ground PDDL expressions over the knowledge base's facts: goals, conditions, effects.

- :mod:`.nodes` — the tree: frozen nodes (``Atom``, ``And``, ``Compare``, ...) with no
  unified-planning objects in them, so the plan executor and the CLI evaluate them
  without loading a planner;
- :mod:`.world_state` — :class:`WorldState`, evaluating them over facts;
- :mod:`.reader` — reading them from PDDL text against a :class:`Signature`, with a
  one-line reason for anything unknown or ill-typed;
- :mod:`.pattern` — names in PDDL text: what a PDDL name is, the objects an expression
  names, fact patterns (``(robot_at *)``).

Everything is importable from this package, as it was from the one module it grew from.
"""

from __future__ import annotations

from executive.planning.expression.nodes import (
    COMPARISONS,
    FALSE,
    TRUE,
    And,
    Arith,
    Atom,
    Compare,
    Const,
    Expression,
    Not,
    Or,
    Value,
    atoms,
    conjunction,
)
from executive.planning.expression.pattern import FactPattern, is_name, named_objects
from executive.planning.expression.reader import (
    Sexp,
    Signature,
    check_syntax,
    parse,
    parse_fact,
)
from executive.planning.expression.world_state import WorldState

__all__ = [
    "COMPARISONS",
    "FALSE",
    "TRUE",
    "And",
    "Arith",
    "Atom",
    "Compare",
    "Const",
    "Expression",
    "FactPattern",
    "Not",
    "Or",
    "Sexp",
    "Signature",
    "Value",
    "WorldState",
    "atoms",
    "check_syntax",
    "conjunction",
    "is_name",
    "named_objects",
    "parse",
    "parse_fact",
]
