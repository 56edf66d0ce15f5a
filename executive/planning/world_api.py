"""The high level's world verbs on the bus (:mod:`executive.bus.api.planning`): the facts
and objects the planner plans from.

Names are read as :mod:`executive.planning.expression` reads them: a fact against the
domain and the objects, a pattern as a fact pattern (its names checked once the domain
is there), an object name as a PDDL name; the objects a goal or a rule names are those
its expression names. ``state/get`` of a new robot waits for its world (it comes with
the domain); a change waits for the high level to plan, and reaches the plan executor
(which checks the plan ahead) and the goal planner.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import Any

from executive.bus.api import planning as api
from executive.bus.service import Context
from executive.planning.deliberation import Deliberation
from executive.planning.expression import (
    FactPattern,
    Signature,
    is_name,
    named_objects,
    parse_fact,
)
from executive.planning.integrity import Trigger
from executive.planning.warm_up import WarmUp
from knowledge.domain import DomainInfo
from knowledge.errors import DuraError, KnowledgeError, did_you_mean
from knowledge.records import Fact, TimedFact
from knowledge.transitions import PlanState

WORLD_WAIT = 25.0  # seconds state/get waits for a new robot's world (callers wait 30)

RefuseObject = Callable[[str, str, DomainInfo], "str | None"]
"""Why an object (name, type) may not be added to the world, or ``None``."""


class WorldApi:
    """Serves the facts and objects of the world.

    Args:
        context: the robot, bus and knowledge base.
        warm_up: the planner's warm-up (a new robot's world comes with it).
        planning: the high level at work, once it plans (waits for it; raises
            :class:`~knowledge.errors.DuraError` with the reason if it does not).
        refuse_object: why a new object may not be added (a fleet's: an object of its
            robot type that is no robot of it).
    """

    def __init__(
        self,
        context: Context,
        warm_up: WarmUp,
        planning: Callable[[], Deliberation],
        refuse_object: RefuseObject | None = None,
    ) -> None:
        self.context = context
        self.warm_up = warm_up
        self.planning = planning
        self.refuse_object = refuse_object

    def serve(self) -> list[Any]:
        """Answer the verbs; returns the queryables."""
        bus = self.context.bus
        return [
            api.STATE_GET.serve(bus, self._state_get),
            api.STATE_SET.serve(bus, lambda r: self._state_change(r, unset=False)),
            api.STATE_UNSET.serve(bus, lambda r: self._state_change(r, unset=True)),
            api.OBJECT_ADD.serve(bus, self._object_add),
            api.OBJECT_REMOVE.serve(bus, self._object_remove),
        ]

    def _state_get(self, request: api.StateQuery) -> api.StateReply:
        pattern = FactPattern.read(request.pattern)
        self.warm_up.wait_for_world(WORLD_WAIT)  # a new robot's world comes with its domain
        kb = self.context.kb
        warm = self.warm_up.warm
        if warm is not None:
            pattern.check(Signature.of(warm.domain, kb.objects()))
        facts = [f for f in kb.facts() if pattern.matches(f)]
        timed = [t for t in kb.timed_facts() if pattern.matches(t.fact)]
        return api.StateReply(facts, kb.objects(), timed or None)

    def _state_change(self, request: api.FactChange, *, unset: bool) -> api.FactReply:
        planning = self.planning()
        kb = self.context.kb
        fact = parse_fact(request.fact, Signature.of(planning.domain, kb.objects()))
        if request.at is not None and request.at > time.time():
            later = Fact(fact.name, fact.args, False) if unset else fact  # it stops holding
            return self._timed(planning, TimedFact(later, request.at), request.source)
        with kb.transaction():
            if unset or fact.value is False:
                kb.update_facts(remove=[fact])
            else:
                kb.set_fact(fact)
            kind = "STATE_UNSET" if unset else "STATE_SET"
            kb.log_event(kind, str(fact), {"source": request.source})
        planning.executor.facts_changed([(fact.name, fact.args)])
        by = "the user" if request.source == "user" else request.source
        planning.goals.wake(f"{fact} {'unset' if unset else 'set'} by {by}")
        return api.FactReply(fact)

    def _timed(self, planning: Deliberation, timed: TimedFact, source: str) -> api.FactReply:
        """Keep a fact that takes effect later; the goal planner plans with it now."""
        kb = self.context.kb
        with kb.transaction():
            kb.add_timed_fact(timed)
            kb.log_event("STATE_TIMED", str(timed.fact), {"source": source, "at": timed.at})
        planning.timed.added()
        by = "the user" if source == "user" else source
        when = time.strftime("%H:%M:%S", time.localtime(timed.at))
        planning.goals.wake(f"{timed.fact} from {when} on, by {by}")
        return api.FactReply(timed.fact, timed.at)

    def _object_add(self, request: api.ObjectAdd) -> api.ObjectAdd:
        domain = self.planning().domain
        name, type_name = request.name, request.type
        kb = self.context.kb
        if type_name not in domain.types:  # `object` too, unless the domain is untyped
            known = sorted(domain.types)
            listed = f"the domain's types: {', '.join(known) or 'none'}"
            if type_name == "object":  # a planning problem has no objects of the root type
                raise DuraError(f"an object needs a type of the domain, not 'object' ({listed})")
            hint = did_you_mean(type_name, known) or f" ({listed})"
            raise DuraError(f"unknown type '{type_name}'{hint}")
        if not is_name(name):
            raise DuraError(f"'{name}' is not a PDDL name (a letter, then letters, digits, - or _)")
        existing = kb.objects().get(name)
        if existing is not None and existing != type_name:
            raise KnowledgeError(f"object '{name}' exists already, of type '{existing}'")
        if existing is None and self.refuse_object is not None:
            refused = self.refuse_object(name, type_name, domain)
            if refused is not None:
                raise DuraError(refused)
        with kb.transaction():
            kb.add_object(name, type_name)
            kb.log_event("OBJECT_ADDED", name, {"type": type_name})
        return api.ObjectAdd(name, type_name)

    def _object_remove(self, request: api.ObjectName) -> api.StateReply:
        """Remove an object and every fact that names it (as PlanSys2 removes an
        instance); refused, with who names it, while an open goal, the current plan or an
        integrity rule does."""
        planning = self.planning()
        name, kb = request.name, self.context.kb
        with kb.transaction():
            objects = kb.objects()
            if name not in objects:
                raise KnowledgeError(f"no object '{name}'{did_you_mean(name, sorted(objects))}")
            users = self._naming(name, planning)
            if users:
                raise DuraError(f"object '{name}' is in use: {'; '.join(users)}")
            facts = [f for f in kb.facts() if name in f.args]
            kb.update_facts(remove=facts)
            kb.remove_object(name)
            kb.log_event(
                "OBJECT_REMOVED",
                name,
                {"type": objects[name], "facts": [str(f) for f in facts], "source": "user"},
            )
        planning.executor.facts_changed()
        planning.goals.wake(f"object {name} removed by the user")
        return api.StateReply(facts, {name: objects[name]})

    def _naming(self, name: str, planning: Deliberation) -> list[str]:
        """Who names an object: open goals, the current plan's steps, integrity rules."""
        kb = self.context.kb
        users = [
            f"goal {g.id} {g.expression} is {g.state.value}"
            for g in kb.open_goals()
            if name in named_objects(g.expression)
        ]
        plan = kb.latest_plan()
        if plan is not None and plan.state in (PlanState.PENDING, PlanState.EXECUTING):
            steps = [f"{s.action}({', '.join(s.args)})" for s in plan.steps if name in s.args]
            if steps:
                users.append(f"plan {plan.id} ({plan.state.value}) has {', '.join(steps)}")
        for rule in planning.integrity.rules:
            condition = rule.subject if rule.trigger is Trigger.CONDITION else ""
            if name in named_objects(rule.goal) | named_objects(condition):
                users.append(f"integrity rule '{rule.name}' ({rule.where})")
        return users
