"""The objects a task asked for by hand names: each goal field that is a parameter of the
task's PDDL action must name an object of the knowledge base (or a constant of the
domain) of the parameter's type or one of its subtypes.

``dura task start move_to --arg start=narnia`` is refused here, before the task exists;
a plan's steps need no check (the planner only names objects it knows).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from knowledge.description import TaskSpec
from knowledge.domain import DomainInfo
from knowledge.errors import KnowledgeError


def check_objects(
    task: TaskSpec, goal: Mapping[str, Any], domain: DomainInfo, objects: Mapping[str, str]
) -> None:
    """Check the objects ``goal`` names for ``task``'s action parameters.

    Args:
        objects: the knowledge base's objects, name → type.

    Raises:
        KnowledgeError: a field names no object of the right type (the first such field).
    """
    action = domain.actions.get(task.action)
    if action is None:
        return  # validation of the description reports it
    types = dict(action.parameters)
    known = {**domain.constants, **objects}
    for field, arg in task.goal.items():
        if arg.parameter is None or field not in goal or arg.parameter not in types:
            continue
        wanted, value = types[arg.parameter], goal[field]
        found = known.get(value) if isinstance(value, str) else None
        if found is not None and domain.is_a(found, wanted):
            continue
        fitting = domain.objects_of(wanted, objects)
        what = f"no object {value!r}" if found is None else f"{value!r} is a {found}, not"
        raise KnowledgeError(
            f"task '{task.action}': {field}={value}: {what} of type '{wanted}' (objects of "
            f"that type: {', '.join(fitting) or 'none'})"
        )
