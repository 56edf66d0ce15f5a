"""What ``dura domain show`` tells about a robot's domain: its types, predicates and
functions, and each action with its parameters, its duration and the task (behavior and
goal fields) that carries it out; from a running robot also which actions cannot run
now and why."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from executive.bus.api.planning import DomainAction, DomainReply, DomainSignature, DomainType
from knowledge.description import GoalArg, RobotDescription
from knowledge.domain import DomainInfo


def describe(
    domain: DomainInfo, robot: RobotDescription, blocked: Mapping[str, str] | None = None
) -> DomainReply:
    """The domain as :data:`executive.bus.api.planning.DOMAIN_SHOW` answers it.

    Args:
        blocked: the actions that cannot run now (permanently faulty components), with
            the reason; ``None`` offline, where nothing is known of faults.
    """
    return DomainReply(
        name=domain.name,
        path=str(domain.path),
        types=[DomainType(t, domain.supertypes.get(t) or "object") for t in domain.types],
        predicates=[DomainSignature(n, tuple(p)) for n, p in domain.predicates.items()],
        functions=[DomainSignature(n, tuple(p)) for n, p in domain.functions.items()],
        actions=[_action(a.name, domain, robot, blocked) for a in domain.actions.values()],
        constants=dict(domain.constants),
    )


def _action(
    name: str, domain: DomainInfo, robot: RobotDescription, blocked: Mapping[str, str] | None
) -> DomainAction:
    action = domain.actions[name]
    task = robot.tasks.get(name)
    return DomainAction(
        name=name,
        parameters=tuple((f"?{p}", t) for p, t in action.parameters),
        durative=action.durative,
        duration=action.duration,
        task=None if task is None else name,
        behavior=None if task is None else task.behavior,
        goal={} if task is None else {k: _goal_arg(v) for k, v in task.goal.items()},
        blocked=None if blocked is None else blocked.get(name),
    )


def _goal_arg(arg: GoalArg) -> Any:
    return f"?{arg.parameter}" if arg.parameter is not None else arg.constant
