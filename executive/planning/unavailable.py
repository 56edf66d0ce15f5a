"""Objects that cannot take part in actions now (a fleet's robot that is lost), compiled
into a problem: every action parameter whose type admits such an object gets the
condition that the object bound to it is available (a static fluent of dura's own,
``dura_available``, true for every other object of that type), at the action's start.
Facts and goals may still name the object; only no step acts with it. The condition is
the planner's alone: the plan's steps leave it out (:func:`is_availability`), since it
is no fact of the knowledge base.
"""

from __future__ import annotations

from collections.abc import Collection
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from unified_planning.model import Fluent, Problem

AVAILABLE = "dura_available_"  # a fluent per user type, with the problem's bookkeeping prefix


def restrict(problem: Problem, unavailable: Collection[str]) -> None:
    """Let no action of ``problem`` (with its objects) take an ``unavailable`` object."""
    from unified_planning.model import DurativeAction, InstantaneousAction, StartTiming
    from unified_planning.model import Fluent as NewFluent

    gone = {name for name in unavailable if problem.has_object(name)}
    if not gone:
        return
    kinds = {problem.object(name).type for name in gone}
    em = problem.environment.expression_manager
    fluents: dict[object, Fluent] = {}  # by the type of the parameters they guard

    def guard(kind: Any) -> Fluent:
        fluent = fluents.get(kind)
        if fluent is None:
            fluent = NewFluent(f"{AVAILABLE}{kind.name}", environment=problem.environment, of=kind)
            problem.add_fluent(fluent, default_initial_value=False)
            for obj in problem.objects(kind):
                if obj.name not in gone:
                    problem.set_initial_value(fluent(em.ObjectExp(obj)), True)
            fluents[kind] = fluent
        return fluent

    for action in problem.actions:
        for parameter in action.parameters:
            if not any(_may_hold(parameter.type, k) for k in kinds):
                continue
            condition = guard(parameter.type)(em.ParameterExp(parameter))
            if isinstance(action, DurativeAction):
                action.add_condition(StartTiming(), condition)
            elif isinstance(action, InstantaneousAction):
                action.add_precondition(condition)


def is_availability(condition: Any) -> bool:
    """Whether a condition of an action is the one :func:`restrict` added."""
    return bool(condition.is_fluent_exp()) and str(condition.fluent().name).startswith(AVAILABLE)


def _may_hold(parameter_type: Any, kind: Any) -> bool:
    """Whether a parameter of ``parameter_type`` may be bound to an object of ``kind``
    (the same type or a subtype of it)."""
    current = kind
    while current is not None:
        if current == parameter_type:
            return True
        current = getattr(current, "father", None)
    return False
