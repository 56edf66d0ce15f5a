"""The high level of the executive (thesis 5.1.2) as one service, and its bus API.

It composes the goal planner, the plan executer and the integrity goal generator on the
robot's knowledge base, with a warm planner worker, and serves the requests of the goal
submission interface (``executive/api/goal/*``, ``plan/show``, ``state/*``,
``object/add``, ``events``, ``status``; payloads in :mod:`executive.bus.keys` and :mod:`executive.bus.payloads`). Every
event logged in the knowledge base is also published on the bus key ``events``.

On start it loads the robot's initial world into an empty knowledge base and plans for
the goals still open there: an executive restarted after a crash carries on with them.
"""

from __future__ import annotations

import contextlib
import logging
import threading
import time
from collections.abc import Callable
from typing import Any

from executive.bus.keys import DIAGNOSES, EVENTS, api
from executive.bus.service import Context, Service
from executive.planning.expression import Signature, parse_fact
from executive.planning.goal_planner import GoalPlanner
from executive.planning.goals import submit
from executive.planning.integrity import IntegrityGoals, IntegrityRule, read_rules
from executive.planning.plan_executer import ExecutionLimits, PlanExecuter, TaskRunner, recover
from executive.planning.planner import Planner
from executive.planning.problem import seed_world
from knowledge.availability import blocked_tasks
from knowledge.domain import read_domain
from knowledge.errors import DuraError, KnowledgeError
from knowledge.records import Event, GoalState, to_plain

log = logging.getLogger("dura.high_level")
FAULT_CHANGES = ("PERMANENT_FAULT", "COMPONENT_RESET")  # events that may block or free tasks

MAX_EVENTS = 10_000  # the most events one request returns


def _int(request: dict[str, Any], key: str) -> int:
    value = request.get(key)
    if not isinstance(value, int) or isinstance(value, bool):
        raise DuraError(f"the request needs an integer '{key}', not {value!r}")
    return value


def _text(request: dict[str, Any], key: str) -> str:
    value = request.get(key)
    if not isinstance(value, str) or not value.strip():
        raise DuraError(f"the request needs a text '{key}', not {value!r}")
    return value


def _number(request: dict[str, Any], key: str) -> float | None:
    value = request.get(key)
    if value is None:
        return None
    if not isinstance(value, int | float) or isinstance(value, bool):
        raise DuraError(f"'{key}' must be a number, not {value!r}")
    return float(value)


class HighLevel(Service):
    """Goal planner, plan executer and integrity goals, served on the bus.

    Args:
        context: the robot, bus and knowledge base.
        runner: carries out plan steps (the task executor's adapter).
        status: extra sections for ``status`` (components, tasks, diagnoses), by name.
        limits: when a running step times out.
    """

    name = "high-level"

    def __init__(
        self,
        context: Context,
        runner: TaskRunner,
        *,
        status: dict[str, Callable[[], Any]] | None = None,
        limits: ExecutionLimits | None = None,
    ) -> None:
        super().__init__(context)
        self.runner = runner
        self.extra_status = dict(status or {})
        self.limits = limits
        self._declared: list[Any] = []
        self._diagnoses: dict[str, Any] = {}
        self._check = threading.Event()
        self._stopping = threading.Event()
        self._integrity_thread: threading.Thread | None = None
        self._relaying = False
        self._blocked: dict[str, str] = {}
        self._faults_changed = threading.Event()  # a permanent fault came or went

    # --- lifecycle -----------------------------------------------------------------------

    def start(self) -> None:
        robot, kb, bus = self.context.robot, self.context.kb, self.context.bus
        self.domain = read_domain(robot.domain)
        seed_world(kb, robot)
        recover(kb)
        rules: list[IntegrityRule] = []
        for path in robot.integrity:
            rules.extend(read_rules(path, robot, self.domain, kb.objects()))
        self.integrity = IntegrityGoals(kb, self.domain, rules)
        self.planner = Planner(robot.planner.engine, robot.planner.timeout)
        self.planner.start(robot.domain)
        self.executer = PlanExecuter(kb, self.runner, robot.tasks, self._replan, self.limits)
        self._blocked = self.blocked()
        self.goals = GoalPlanner(kb, self.domain, self.planner, self.executer, blocked=self.blocked)
        self._relaying = True
        kb.add_listener(self._on_event)
        self._declared = [bus.subscribe(DIAGNOSES, self._on_diagnoses)]
        for verb, handler in self._api().items():
            self._declared.append(bus.serve(api(verb), handler, threaded=True))
        self._stopping.clear()
        self._integrity_thread = threading.Thread(
            target=self._integrity_loop, name="integrity-goals", daemon=True
        )
        self._integrity_thread.start()
        self.executer.start()
        self.goals.start()

    def stop(self) -> None:
        if self._integrity_thread is None:
            return
        self._stopping.set()
        self._check.set()
        self._integrity_thread.join()
        self._integrity_thread = None
        for entity in self._declared:
            with contextlib.suppress(Exception):
                entity.undeclare()
        self._declared = []
        self.goals.stop()
        self.executer.stop()
        self.planner.close()
        self._relaying = False

    def _replan(self, reason: str) -> None:
        self.goals.replan(reason)

    # --- events, diagnoses and integrity goals ---------------------------------------------

    def _on_event(self, event: Event) -> None:
        if not self._relaying:
            return
        self.context.bus.publish(EVENTS, to_plain(event))
        if event.kind in FAULT_CHANGES:
            self._faults_changed.set()
        if not event.kind.startswith("INTEGRITY_"):
            self._check.set()

    def _on_diagnoses(self, message: Any) -> None:
        payload = message.payload
        self._diagnoses = dict(payload)
        self.integrity.diagnosed(payload)
        self._check.set()

    def _integrity_loop(self) -> None:
        """Check the integrity rules when something changed, and when a rule is due."""
        while not self._stopping.is_set():
            due = self.integrity.next_check()
            wait = None if due is None else max(0.0, due - time.time())
            self._check.wait(wait)
            self._check.clear()
            if self._stopping.is_set():
                return
            try:
                posted = self.integrity.check()
            except Exception:  # a broken check must not end the generator
                log.exception("integrity check failed")
                continue
            for goal in posted:
                self.goals.wake(f"integrity goal {goal.id} posted")
            if self._faults_changed.is_set():
                self._faults_changed.clear()
                self._check_blocked()

    def blocked(self) -> dict[str, str]:
        """The tasks that cannot run with the permanently faulty components, and why."""
        faulty = [c.name for c in self.context.kb.components() if c.permanent_fault]
        return blocked_tasks(self.context.robot, faulty)

    def _check_blocked(self) -> None:
        """Replan when a task can no longer run, or can run again (after a reset)."""
        blocked = self.blocked()
        if blocked.keys() == self._blocked.keys():
            return
        lost = sorted(blocked.keys() - self._blocked.keys())
        back = sorted(self._blocked.keys() - blocked.keys())
        self._blocked = blocked
        if lost:
            self.goals.replan(f"{', '.join(lost)} can no longer run ({blocked[lost[0]]})")
        else:
            self.goals.replan(f"{', '.join(back)} can run again")

    # --- the bus API ---------------------------------------------------------------------

    def _api(self) -> dict[str, Callable[[dict[str, Any]], dict[str, Any]]]:
        return {
            "goal/add": self._goal_add,
            "goal/list": self._goal_list,
            "goal/show": self._goal_show,
            "goal/cancel": self._goal_cancel,
            "plan/show": self._plan_show,
            "state/get": self._state_get,
            "state/set": lambda r: self._state_change(r, unset=False),
            "state/unset": lambda r: self._state_change(r, unset=True),
            "object/add": self._object_add,
            "events": self._events,
            "status": self._status,
        }

    def _goal_add(self, request: dict[str, Any]) -> dict[str, Any]:
        priority = request.get("priority", 0)
        if not isinstance(priority, int) or isinstance(priority, bool):
            raise DuraError(f"'priority' must be an integer, not {priority!r}")
        source = request.get("source", "user")
        goal = submit(
            self.context.kb,
            self.domain,
            _text(request, "expression"),
            priority=priority,
            deadline=_number(request, "deadline"),
            source=str(source),
        )
        self.goals.wake(f"goal {goal.id} added")
        return {"goal": to_plain(goal)}

    def _goal_list(self, request: dict[str, Any]) -> dict[str, Any]:
        wanted = request.get("states")
        try:
            states = None if wanted is None else [GoalState(s) for s in wanted]
        except (ValueError, TypeError):
            names = ", ".join(s.value for s in GoalState)
            raise DuraError(f"'states' must list goal states ({names}), not {wanted!r}") from None
        return {"goals": to_plain(self.context.kb.goals(states))}

    def _goal_show(self, request: dict[str, Any]) -> dict[str, Any]:
        kb = self.context.kb
        goal_id = _int(request, "id")
        goal = kb.goal(goal_id)
        subject = f"goal {goal_id}"
        events = [e for e in kb.events() if e.subject == subject or _names_goal(e, goal_id)]
        return {"goal": to_plain(goal), "events": to_plain(events)}

    def _goal_cancel(self, request: dict[str, Any]) -> dict[str, Any]:
        kb = self.context.kb
        goal = kb.goal(_int(request, "id"))
        if not goal.state.is_open:
            raise KnowledgeError(f"goal {goal.id} is {goal.state.value} already")
        self.goals.cancel(goal.id)
        return {"goal": to_plain(kb.goal(goal.id))}

    def _plan_show(self, request: dict[str, Any]) -> dict[str, Any]:
        plan = self.context.kb.latest_plan()
        return {
            "plan": None if plan is None else to_plain(plan),
            "execution": self.executer.status(),
        }

    def _state_get(self, request: dict[str, Any]) -> dict[str, Any]:
        pattern = request.get("pattern") or ""
        if not isinstance(pattern, str):
            raise DuraError(f"'pattern' must be a text, not {pattern!r}")
        kb = self.context.kb
        words = pattern.strip("() ").split()
        facts = [f for f in kb.facts() if _matches(words, f.name, f.args)]
        return {"facts": [_fact(f) for f in facts], "objects": kb.objects()}

    def _state_change(self, request: dict[str, Any], *, unset: bool) -> dict[str, Any]:
        kb = self.context.kb
        fact = parse_fact(_text(request, "fact"), Signature.of(self.domain, kb.objects()))
        with kb.transaction():
            if unset or fact.value is False:
                kb.update_facts(remove=[fact])
            else:
                kb.set_fact(fact)
            kb.log_event("STATE_UNSET" if unset else "STATE_SET", str(fact), {"source": "user"})
        self.executer.facts_changed()
        self.goals.wake(f"{fact} {'unset' if unset else 'set'} by the user")
        return {"fact": _fact(fact)}

    def _object_add(self, request: dict[str, Any]) -> dict[str, Any]:
        name, type_name = _text(request, "name"), _text(request, "type")
        kb = self.context.kb
        if type_name not in self.domain.types and type_name != "object":
            known = ", ".join(sorted(self.domain.types)) or "none"
            raise DuraError(f"unknown type '{type_name}' (the domain's types: {known})")
        if not name.replace("_", "").replace("-", "").isalnum() or not name[0].isalpha():
            raise DuraError(f"'{name}' is not a PDDL name (a letter, then letters, digits, - or _)")
        existing = kb.objects().get(name)
        if existing is not None and existing != type_name:
            raise KnowledgeError(f"object '{name}' exists already, of type '{existing}'")
        with kb.transaction():
            kb.add_object(name, type_name)
            kb.log_event("OBJECT_ADDED", name, {"type": type_name})
        return {"name": name, "type": type_name}

    def _events(self, request: dict[str, Any]) -> dict[str, Any]:
        after = request.get("after", 0)
        limit = request.get("limit", 100)
        kind = request.get("kind")
        for key, value in (("after", after), ("limit", limit)):
            if not isinstance(value, int) or isinstance(value, bool) or value < 0:
                raise DuraError(f"'{key}' must be a non-negative integer, not {value!r}")
        if kind is not None and not isinstance(kind, str):
            raise DuraError(f"'kind' must be a text, not {kind!r}")
        events = self.context.kb.events(after=after, kind=kind, limit=min(limit, MAX_EVENTS))
        return {"events": to_plain(events)}

    def _status(self, request: dict[str, Any]) -> dict[str, Any]:
        kb = self.context.kb
        plan = kb.latest_plan()
        status: dict[str, Any] = {
            "robot": self.context.robot.name,
            "goals": to_plain(kb.goals()),
            "plan": None if plan is None else to_plain(plan),
            "execution": self.executer.status(),
            "diagnoses": self._diagnoses,
            "faults": to_plain([c for c in kb.components() if c.fault_count or c.permanent_fault]),
        }
        for name, section in self.extra_status.items():
            try:
                status[name] = section()
            except DuraError as e:
                status[name] = {"error": str(e)}
        return status


def _names_goal(event: Event, goal_id: int) -> bool:
    goals = event.data.get("goals") if isinstance(event.data, dict) else None
    return isinstance(goals, list) and goal_id in goals


def _matches(words: list[str], name: str, args: tuple[str, ...]) -> bool:
    """``robot_at``, ``(robot_at lab)``, ``(robot_at *)``: a name and leading arguments."""
    if not words:
        return True
    if words[0] not in ("*", name):
        return False
    return all(w in ("*", a) for w, a in zip(words[1:], args, strict=False))


def _fact(fact: Any) -> dict[str, Any]:
    return {"name": fact.name, "args": list(fact.args), "value": fact.value, "text": str(fact)}
