"""Build unified-planning problems from the knowledge base, and read worlds from PDDL.

A planning problem is the robot's domain, the knowledge base's objects and facts
(predicates and numeric functions) and the open goals. Expressions cross between
dura's ground expressions (:mod:`executive.planning.expression`) and UP's ``FNode`` here, in
both directions, and nowhere else.

Deadlines: UP's timed goals say a goal holds *at* an instant, and Kairos (the default
engine) does not accept them. A deadline means "reached by then", so it is compiled
into what every temporal engine here accepts: a timed initial literal closes a window
at the deadline, and an instantaneous bookkeeping action ``dura_reach_goal_<id>``,
possible only while the window is open and the goal holds, marks the goal reached.
The goal must also hold at the end, like every goal.
"""

from __future__ import annotations

import functools
import time
from collections.abc import Collection, Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from fractions import Fraction
from pathlib import Path
from typing import TYPE_CHECKING, Any

from executive.bus.clock import Clock
from executive.planning.expression import (
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
    conjunction,
)
from executive.planning.goals import GoalSpec
from executive.planning.metric import TOTAL_COST, Metric
from executive.planning.unavailable import restrict
from knowledge.domain import parse, parse_problem, type_name
from knowledge.errors import DomainError, located
from knowledge.knowledge_base import KnowledgeBase
from knowledge.records import Fact, TimedFact
from knowledge.sources import read_text

if TYPE_CHECKING:
    from unified_planning.model import FNode, Problem

    from knowledge.description import RobotDescription

BOOKKEEPING = "dura_"  # prefix of the fluents and actions compiled for deadlines
REACH_GOAL = "dura_reach_goal_"


@dataclass(frozen=True)
class TimedLiteral:
    """A fact that becomes true (or false, or takes a value) at a time: PDDL's timed
    initial literal, ``(at 10 (door_open d1))``; ``at`` in seconds after the plan starts
    (the knowledge base keeps a :class:`~knowledge.records.TimedFact` at a wall-clock
    time: :func:`literals`)."""

    at: float
    fact: Fact

    def __str__(self) -> str:
        return f"(at {self.at:g} {self.fact})"


@dataclass(frozen=True)
class World:
    """The objects (name → type) and facts a problem starts from, the facts that
    change on their own later (``timed``), and the objects that take part in no action
    now (``unavailable``: a fleet's lost robots, :mod:`.unavailable`)."""

    objects: Mapping[str, str] = field(default_factory=dict)
    facts: tuple[Fact, ...] = ()
    timed: tuple[TimedLiteral, ...] = ()
    unavailable: frozenset[str] = frozenset()  # objects that cannot act now (unavailable)


def literals(timed: Iterable[TimedFact], now: float, clock: Clock) -> tuple[TimedLiteral, ...]:
    """The knowledge base's timed facts still to come at ``now`` (wall clock), as timed
    literals of a plan that starts now (in robot seconds)."""
    return tuple(TimedLiteral(clock.robot(t.at - now), t.fact) for t in timed if t.at > now)


def live_world(
    objects: Mapping[str, str],
    facts: Iterable[Fact],
    kb: KnowledgeBase,
    clock: Clock,
    unavailable: Iterable[str] = (),
) -> World:
    """The world to plan from now: objects, facts, the knowledge base's timed facts, and
    the objects that cannot act now."""
    timed = literals(kb.timed_facts(), time.time(), clock)
    return World(objects, tuple(facts), timed, frozenset(unavailable))


# --- dura expressions -> UP ----------------------------------------------------------


def to_fnode(expression: Expression, problem: Problem) -> FNode:
    """A ground expression as a UP expression of ``problem``."""
    em = problem.environment.expression_manager
    e = expression
    if isinstance(e, Const):
        if isinstance(e.value, bool):
            return em.Bool(e.value)
        return em.Real(Fraction(str(e.value)))
    if isinstance(e, (Atom, Value)):
        fluent = problem.fluent(e.name)
        return em.FluentExp(fluent, [em.ObjectExp(problem.object(a)) for a in e.args])
    if isinstance(e, Not):
        return em.Not(to_fnode(e.arg, problem))
    if isinstance(e, And):
        return em.And(*(to_fnode(a, problem) for a in e.args))
    if isinstance(e, Or):
        return em.Or(*(to_fnode(a, problem) for a in e.args))
    if isinstance(e, Compare):
        left, right = to_fnode(e.left, problem), to_fnode(e.right, problem)
        ops = {"<": em.LT, "<=": em.LE, ">": em.GT, ">=": em.GE, "=": em.Equals}
        return ops[e.op](left, right)
    if isinstance(e, Arith):
        args = [to_fnode(a, problem) for a in e.args]
        if e.op == "-" and len(args) == 1:
            return em.Minus(em.Real(Fraction(0)), args[0])
        combine = {"+": em.Plus, "-": em.Minus, "*": em.Times, "/": em.Div}[e.op]
        out = args[0]
        for a in args[1:]:
            out = combine(out, a)
        return out
    raise TypeError(f"not an expression: {e!r}")


# --- UP -> dura expressions ----------------------------------------------------------


def from_fnode(node: FNode, problem: Problem, env: Mapping[str, str] | None = None) -> Expression:
    """A UP expression as a ground expression; ``env`` binds parameters and variables.

    Quantifiers are expanded over the problem's objects.

    Raises:
        DomainError: the expression uses something dura cannot evaluate.
    """
    env = env or {}
    n = node
    if n.is_bool_constant():
        return TRUE if n.bool_constant_value() else FALSE
    if n.is_int_constant() or n.is_real_constant():
        return Const(float(n.constant_value()))
    if n.is_fluent_exp():
        args = tuple(_object_name(a, env) for a in n.args)
        fluent = n.fluent()
        return Atom(fluent.name, args) if fluent.type.is_bool_type() else Value(fluent.name, args)
    if n.is_not():
        inner = from_fnode(n.arg(0), problem, env)
        return Const(not inner.value) if isinstance(inner, Const) else Not(inner)
    if n.is_and():
        return conjunction(from_fnode(a, problem, env) for a in n.args)
    if n.is_or():
        return Or(tuple(from_fnode(a, problem, env) for a in n.args))
    if n.is_implies():
        a, b = (from_fnode(x, problem, env) for x in n.args)
        return Or((Not(a), b))
    if n.is_iff():
        a, b = (from_fnode(x, problem, env) for x in n.args)
        return Or((And((a, b)), And((Not(a), Not(b)))))
    if n.is_exists() or n.is_forall():
        parts = [
            from_fnode(n.arg(0), problem, {**env, **binding})
            for binding in bindings(n.variables(), problem)
        ]
        return conjunction(parts) if n.is_forall() else Or(tuple(parts))
    if (
        n.is_equals()
        and not n.arg(0).type.is_bool_type()
        and (n.arg(0).type.is_user_type() or n.arg(1).type.is_user_type())
    ):
        return Const(_object_name(n.arg(0), env) == _object_name(n.arg(1), env))
    comparisons = {"is_lt": "<", "is_le": "<=", "is_equals": "="}
    for test, op in comparisons.items():
        if getattr(n, test)():
            return Compare(
                op, from_fnode(n.arg(0), problem, env), from_fnode(n.arg(1), problem, env)
            )
    arithmetic = {"is_plus": "+", "is_minus": "-", "is_times": "*", "is_div": "/"}
    for test, op in arithmetic.items():
        if getattr(n, test)():
            return Arith(op, tuple(from_fnode(a, problem, env) for a in n.args))
    raise DomainError(f"dura cannot evaluate '{n}' in the knowledge base")


def _object_name(node: FNode, env: Mapping[str, str]) -> str:
    if node.is_object_exp():
        return str(node.object().name)
    if node.is_parameter_exp():
        return env[node.parameter().name]
    if node.is_variable_exp():
        return env[node.variable().name]
    raise DomainError(f"dura cannot evaluate '{node}': expected an object")


def bindings(variables: Sequence[Any], problem: Problem) -> list[dict[str, str]]:
    out: list[dict[str, str]] = [{}]
    for v in variables:
        names = [o.name for o in problem.objects(v.type)]
        out = [{**b, v.name: name} for b in out for name in names]
    return out


# --- problems ------------------------------------------------------------------------


def build(
    domain: Problem,
    world: World,
    goals: Sequence[GoalSpec],
    blocked: Collection[str] = (),
    metric: Metric | None = None,
) -> Problem:
    """A problem: the domain (a UP problem without objects), a world (with its timed
    facts) and goals, without the ``blocked`` actions, optimising ``metric``. For PDDL's
    action costs the domain must be parsed with them (:func:`costs_problem`).

    Raises:
        DomainError: an object, fact or goal does not fit the domain.
    """
    # here, not at the top: the executive imports this module (World) and leaves
    # unified-planning to its planner worker
    from unified_planning.model import Fluent, GlobalStartTiming, InstantaneousAction, Object

    problem = domain.clone()
    if blocked:
        kept = [a for a in problem.actions if a.name not in blocked]
        problem.clear_actions()
        problem.add_actions(kept)
    for name, kind in world.objects.items():
        if problem.has_object(name):
            continue
        if not problem.has_type(kind):
            raise DomainError(f"object '{name}' has unknown type '{kind}'")
        problem.add_object(Object(name, problem.user_type(kind)))
    costs = _has_action_costs(problem)
    for fact in world.facts:
        if costs and fact.name == TOTAL_COST.name:
            continue  # compiled into the actions' costs, as UP's reader does
        atom, value = _assignment(fact, problem)
        try:
            problem.set_initial_value(atom, value)
        except Exception as e:  # UP raises its own errors for unknown objects and types
            raise DomainError(f"fact {fact}: {e}") from e
    for timed in world.timed:
        atom, value = _assignment(timed.fact, problem)
        try:
            problem.add_timed_effect(GlobalStartTiming(_time(timed.at)), atom, value)
        except Exception as e:
            raise DomainError(f"timed fact {timed}: {e}") from e
    _set_metric(problem, metric, costs)
    restrict(problem, world.unavailable)
    for goal in goals:
        target = to_fnode(goal.expression, problem)
        problem.add_goal(target)
        if goal.deadline is None:
            continue
        window = Fluent(f"{BOOKKEEPING}before_deadline_{goal.id}", environment=problem.environment)
        reached = Fluent(f"{BOOKKEEPING}reached_{goal.id}", environment=problem.environment)
        problem.add_fluent(window, default_initial_value=False)
        problem.add_fluent(reached, default_initial_value=False)
        problem.set_initial_value(window(), True)
        problem.add_timed_effect(GlobalStartTiming(_time(goal.deadline)), window(), False)
        reach = InstantaneousAction(f"{REACH_GOAL}{goal.id}", _env=problem.environment)
        reach.add_precondition(target)
        reach.add_precondition(window())
        reach.add_effect(reached(), True)
        problem.add_action(reach)
        problem.add_goal(reached())
    return problem


def _time(seconds: float) -> Fraction:
    return Fraction(str(round(seconds, 3)))


def _assignment(fact: Fact, problem: Problem) -> tuple[FNode, FNode]:
    """A fact as UP's (fluent expression, value)."""
    if not problem.has_fluent(fact.name):
        raise DomainError(f"fact {fact}: unknown predicate or function '{fact.name}'")
    em = problem.environment.expression_manager
    try:
        atom = to_fnode(Atom(fact.name, fact.args), problem)
    except Exception as e:  # UP raises its own errors for unknown objects
        raise DomainError(f"fact {fact}: {e}") from e
    if isinstance(fact.value, bool):
        return atom, em.Bool(fact.value)
    return atom, em.Real(Fraction(str(fact.value)))


def _has_action_costs(problem: Problem) -> bool:
    return any(type(m).__name__ == "MinimizeActionCosts" for m in problem.quality_metrics)


def _set_metric(problem: Problem, metric: Metric | None, costs: bool) -> None:
    """Give the problem ``metric`` (the domain's action costs stay only for it)."""
    from unified_planning.model import metrics  # here: as in build()

    if metric is not None and metric.expression == TOTAL_COST and costs:
        return
    problem.clear_quality_metrics()
    if metric is None:
        return
    if metric.expression is None:
        problem.add_quality_metric(metrics.MinimizeMakespan(environment=problem.environment))
        return
    try:
        target = to_fnode(metric.expression, problem)
    except Exception as e:
        raise DomainError(f"metric '{metric}': {e}") from e
    kind = (
        metrics.MinimizeExpressionOnFinalState
        if metric.minimize
        else metrics.MaximizeExpressionOnFinalState
    )
    problem.add_quality_metric(kind(target, environment=problem.environment))


def metric_of(problem: Problem) -> Metric | None:
    """The metric of a parsed problem (PDDL's ``:metric``), if it has one.

    Raises:
        DomainError: a metric dura cannot carry to the engine.
    """
    for m in problem.quality_metrics:
        name = type(m).__name__
        if name == "MinimizeMakespan":
            return Metric()
        if name == "MinimizeActionCosts":
            return Metric(True, TOTAL_COST)
        if name in ("MinimizeExpressionOnFinalState", "MaximizeExpressionOnFinalState"):
            return Metric(name.startswith("Minimize"), from_fnode(m.expression, problem))
        raise DomainError(f"dura cannot carry the metric '{m}' to an engine")
    return None


def frozen(problem: Problem) -> Problem:
    """The same problem, computing its kind only once.

    unified-planning recomputes ``Problem.kind`` at every look (walking every action and
    expression), and one solve, validation and conversion looks 17 times: a third of the
    worker's time. A frozen problem keeps the kind it computed first (its clones do not:
    they are new problems); change nothing in it afterwards. The problem stays a UP
    ``Problem`` (engines dispatch on its type): ``Problem.kind`` learns to look for the
    kept kind, once per process.
    """
    _keep_kinds()
    problem.__dict__[_KIND] = None  # computed at the first look
    return problem


_KIND = "_dura_kind"


@functools.cache
def _keep_kinds() -> None:
    from unified_planning.model import Problem  # here: as in build()

    computed = Problem.kind

    def kind(self: Problem) -> Any:
        kept = self.__dict__
        if _KIND not in kept:
            return computed.fget(self)
        if kept[_KIND] is None:
            kept[_KIND] = computed.fget(self)
        return kept[_KIND]

    Problem.kind = property(kind, doc=computed.__doc__)


def world_of(problem: Problem, domain: Problem | None = None) -> World:
    """The objects, explicit initial facts and timed facts of a parsed problem (domain
    constants left out).

    Raises:
        DomainError: a timed fact that is not a fact at a time after the start.
    """
    constants = {o.name for o in domain.all_objects} if domain is not None else set()
    objects = {o.name: type_name(o.type) for o in problem.all_objects if o.name not in constants}
    facts: list[Fact] = []
    for atom, value in problem.explicit_initial_values.items():
        args = tuple(str(a.object().name) for a in atom.args)
        if value.is_bool_constant():
            if value.bool_constant_value():
                facts.append(Fact(atom.fluent().name, args, True))
        else:
            facts.append(Fact(atom.fluent().name, args, float(value.constant_value())))
    timed = [
        TimedLiteral(float(timing.delay), _fact_of(effect))
        for timing, effects in problem.timed_effects.items()
        for effect in effects
        if timing.is_from_start()
    ]
    if len(timed) != sum(len(e) for e in problem.timed_effects.values()):
        raise DomainError("dura plans only with timed facts counted from the start")
    return World(
        objects,
        tuple(sorted(facts, key=lambda f: (f.name, f.args))),
        tuple(sorted(timed, key=lambda t: (t.at, t.fact.name, t.fact.args))),
    )


def _fact_of(effect: Any) -> Fact:
    """A timed initial literal's effect as a fact."""
    if not effect.is_assignment() or effect.is_conditional():
        raise DomainError(f"dura plans only with timed facts, not with '{effect}'")
    args = tuple(str(a.object().name) for a in effect.fluent.args)
    value = effect.value
    if value.is_bool_constant():
        return Fact(effect.fluent.fluent().name, args, bool(value.bool_constant_value()))
    return Fact(effect.fluent.fluent().name, args, float(value.constant_value()))


def read_problem(
    domain: Path, problem_file: Path, parsed: Problem | None = None
) -> tuple[World, Expression, Metric | None]:
    """The world, the goal and the metric of a PDDL problem file (``parsed``: the domain,
    parsed already).

    Raises:
        DomainError: the file cannot be read or does not fit the domain (``file:line``).
    """
    try:
        text = read_text(problem_file)
    except (OSError, UnicodeDecodeError) as e:
        raise DomainError(located(problem_file, None, f"cannot read: {e}")) from e
    problem = parse_problem(domain, text, str(problem_file), domain_checked=parsed is not None)
    try:
        goal = conjunction(from_fnode(g, problem) for g in problem.goals)
        world = world_of(problem, parsed if parsed is not None else parse(domain))
        return world, goal, metric_of(problem)
    except DomainError as e:
        raise DomainError(located(problem_file, None, str(e))) from e


def read_world(
    domain: Path, problem_file: Path, parsed: Problem | None = None
) -> tuple[World, Expression]:
    """The world and the goal of a PDDL problem file (see :func:`read_problem`)."""
    world, goal, _ = read_problem(domain, problem_file, parsed)
    return world, goal


def seed_world(kb: KnowledgeBase, robot: RobotDescription) -> bool:
    """Load the robot's ``problem:`` file into a knowledge base that has no world yet.

    Returns whether it loaded anything. The problem's goal is not submitted.
    """
    if robot.problem is None or kb.objects() or kb.facts():
        return False
    world, _ = read_world(robot.domain, robot.problem)
    return seed(kb, world, robot.problem)


def seed(kb: KnowledgeBase, world: World, source: Path) -> bool:
    """Load a world (read from ``source``) into a knowledge base that has none yet;
    whether it did."""
    with kb.transaction():
        if kb.objects() or kb.facts():
            return False
        for name, kind in world.objects.items():
            kb.add_object(name, kind)
        kb.update_facts(add=world.facts)
        kb.log_event("WORLD_SEEDED", str(source), {"objects": len(world.objects)})
    return True
