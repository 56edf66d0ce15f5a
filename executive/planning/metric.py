"""What a plan optimises: PDDL's ``:metric``, or a robot description's ``planner:
metric:``, as dura carries it from the files to the engine (the planner's worker turns it
into unified-planning's quality metric, :func:`executive.planning.problem.build`)."""

from __future__ import annotations

from dataclasses import dataclass

from executive.planning.expression import Arith, Atom, Const, Expression, Value
from executive.planning.expression.reader import Sexp, read_sexp, show_sexp
from knowledge.errors import DomainError

TOTAL_COST = Value("total-cost", ())  # PDDL's action costs, a metric of its own in UP


@dataclass(frozen=True)
class Metric:
    """What a plan optimises: the makespan (``expression`` None), PDDL's action costs
    (:data:`TOTAL_COST`) or the final value of a numeric expression."""

    minimize: bool = True
    expression: Expression | None = None

    def __str__(self) -> str:
        what = "makespan" if self.expression is None else _pddl(self.expression)
        return f"{'minimize' if self.minimize else 'maximize'} {what}"


def read_metric(text: str) -> Metric:
    """A metric as a robot description writes it: ``minimize makespan``, ``minimize
    (total-time)``, ``minimize (total-cost)``, ``maximize (function objects...)`` or an
    arithmetic expression of such values (checked against the domain when planning).

    Raises:
        DomainError: the text is not a metric.
    """
    direction, _, what = text.strip().partition(" ")
    what = what.strip()
    try:
        if direction not in ("minimize", "maximize"):
            raise ValueError("it must start with 'minimize' or 'maximize'")
        if what in ("makespan", "(total-time)"):
            return Metric(direction == "minimize")
        return Metric(direction == "minimize", _numeric(read_sexp(what)))
    except (ValueError, RecursionError) as e:
        raise DomainError(f"metric '{text}': {e}") from e


def _numeric(s: Sexp) -> Expression:
    if isinstance(s, str):
        return Const(float(s))  # ValueError for a bare name
    if s and s[0] in ("+", "-", "*", "/") and len(s) > 2:
        return Arith(str(s[0]), tuple(_numeric(a) for a in s[1:]))
    if s and all(isinstance(a, str) for a in s):
        return Value(str(s[0]), tuple(str(a) for a in s[1:]))
    raise ValueError(f"expected a function's value or arithmetic, not {show_sexp(s)}")


def _pddl(e: Expression) -> str:
    if isinstance(e, (Atom, Value)):
        return "(" + " ".join((e.name, *e.args)) + ")"
    if isinstance(e, Const):
        return f"{e.value:g}" if not isinstance(e.value, bool) else str(e.value).lower()
    if isinstance(e, Arith):
        return "(" + " ".join((e.op, *(_pddl(a) for a in e.args))) + ")"
    return str(e)


def costs_problem(name: str) -> str:
    """A problem text with nothing but PDDL's action-costs metric, for domain ``name``:
    parsed with the domain, UP compiles ``total-cost`` into the actions' costs."""
    return (
        f"(define (problem dura-action-costs) (:domain {name})"
        " (:init (= (total-cost) 0)) (:goal (and))"
        " (:metric minimize (total-cost)))"
    )
