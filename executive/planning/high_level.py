"""The high level of the executive (thesis 5.1.2) as one service, and its bus API.

It composes the goal planner, the plan executor and the integrity goal generator on the
robot's knowledge base, with a warm planner worker, and serves the requests of the goal
submission interface as declared once in :mod:`executive.bus.api.planning` (goals,
plans, the world's facts and objects, events, status); the declared payload types check
every request before a handler sees it. Every event logged in the knowledge base is
also published on the bus key ``events``; the events other processes publish there (a
task executor or repair rules that run apart) are followed as its own. ``status`` and
``plan/show`` answer from the snapshots the plan executor and the goal planner keep:
they never wait behind a step being dispatched or a plan being computed.

On start it first takes back what a killed executive's unfinished steps did
(:mod:`executive.planning.recovery`) and answers on the bus; then, in the background, its
planner worker loads unified-planning and parses the domain (the executive process
itself never imports unified-planning): the robot's tasks are checked against the
domain, the robot's initial world is loaded into an empty knowledge base, and the goal
planner begins with the goals still open there: an executive restarted after a crash
carries on with them. Until then ``status``, ``goal/list``, ``events`` and the other
readers answer at once (``state/get`` of a new robot waits for its world); a request
that needs the domain (a goal, a fact, an object) waits for it. A domain that does not
fit the robot ends the executive (``on_failure``) with the one-line reason.

The robot's sensing rules (:mod:`executive.planning.sensing`) read their topics through
the topic sources it is given (ROS 2) or the bus. A change of the world from outside the
plan (a fact or object set, a component reset or repaired) reaches the plan executor,
which checks the plan ahead, and the goal planner, which looks again at unreachable
goals; any change of facts reaches the maintenance goals.
"""

from __future__ import annotations

import contextlib
import logging
import re
import threading
from collections.abc import Callable, Sequence
from typing import Any

from executive.bus.api import planning as api
from executive.bus.clock import Clock, system_clock
from executive.bus.keys import DIAGNOSES, EVENTS
from executive.bus.payloads import DiagnosisInfo
from executive.bus.service import Context, Service
from executive.bus.session import Handler, Message
from executive.bus.topic_source import Subscription, TopicSource
from executive.bus.verb import Empty
from executive.planning.domain_description import describe
from executive.planning.dry_run import dry_run
from executive.planning.expression import Signature, parse_fact
from executive.planning.goal_planner import GoalPlanner, PlannerStatus
from executive.planning.goals import submit
from executive.planning.integrity import IntegrityGoals, IntegrityRule, Trigger, read_rules
from executive.planning.plan_executor import (
    ExecutionLimits,
    ExecutionStatus,
    PlanExecutor,
    TaskRunner,
)
from executive.planning.planner import Planner
from executive.planning.problem import seed
from executive.planning.recovery import recover
from executive.planning.sensing import Sensing
from knowledge.availability import blocked_tasks
from knowledge.errors import ConfigError, DuraError, KnowledgeError, did_you_mean
from knowledge.records import Event, Fact, to_plain
from knowledge.transitions import PlanState

log = logging.getLogger("dura.high_level")
FAULT_CHANGES = ("PERMANENT_FAULT", "COMPONENT_RESET")  # events that may block or free tasks
# events of the world changing outside the plan, and of the plan's own steps changing facts
OUTSIDE_CHANGES = ("STATE_SET", "STATE_UNSET", "OBJECT_ADDED", "COMPONENT_RESET", "REPAIR")
PLAN_CHANGES = ("START", "END", "FAIL", "CANCEL")
SECTIONS = ("tasks", "components")  # what other services add to ``status``

MAX_EVENTS = 10_000  # the most events one request returns
WARM_UP_WAIT = 25.0  # seconds a request waits for the planner at start (callers wait 30)


class HighLevel(Service):
    """Goal planner, plan executor and integrity goals, served on the bus.

    Args:
        context: the robot, bus and knowledge base.
        runner: carries out plan steps (the task executor's adapter), or how to get it
            once :meth:`start` is called (the composition root serves the API before it
            starts the task executor).
        status: the sections other services add to ``status`` (``tasks`` from the task
            executor, ``components`` from the launcher), by name.
        limits: when a running step times out.
        on_failure: called (from a thread of its own) with the reason when the high level
            cannot start (the domain does not fit the robot, the planner does not start);
            without it the reason is logged. Requests that need the planner then fail
            with it.
        clock: robot time (default: this process's, from ``DURA_TIME_SCALE``).
        sources: topics not on the bus (ROS 2) that sensing rules may read; the
            composition root may set ``sources`` until :meth:`start`.
    """

    name = "high-level"

    def __init__(
        self,
        context: Context,
        runner: TaskRunner | Callable[[], TaskRunner],
        *,
        status: dict[str, Callable[[], Any]] | None = None,
        limits: ExecutionLimits | None = None,
        on_failure: Callable[[str], None] | None = None,
        clock: Clock | None = None,
        sources: Sequence[TopicSource] = (),
    ) -> None:
        super().__init__(context)
        self.clock = clock or system_clock()
        self.sources = tuple(sources)
        self.runner = runner
        self.extra_status = dict(status or {})
        unknown = sorted(set(self.extra_status) - set(SECTIONS))
        if unknown:
            raise ValueError(f"status has no section {', '.join(unknown)} (only {SECTIONS})")
        self.limits = limits
        self._declared: list[Any] = []
        self._diagnoses: dict[str, Any] = {}
        self._check = threading.Event()
        self._stopping = threading.Event()
        self._integrity_thread: threading.Thread | None = None
        self._relaying = False
        self._blocked: dict[str, str] = {}
        self._faults_changed = threading.Event()  # a permanent fault came or went
        self.on_failure = on_failure
        self._ready = threading.Event()  # the planner parsed the domain; goals are planned
        self._failure: str | None = None  # why the high level could not start
        self._warm_up: threading.Thread | None = None
        self._begin = threading.Event()  # start() was called: the other services run
        self._seeded = threading.Event()  # the knowledge base holds the robot's world
        self._lock = threading.Lock()  # the diagnoses and the integrity goals' start
        self._running: list[Callable[[], None]] = []  # how to stop what started, in order

    # --- lifecycle -----------------------------------------------------------------------

    def start(self) -> None:
        """Open (if not yet), and begin planning as soon as the planner is warm."""
        self.open()
        self._begin.set()

    def open(self) -> None:
        """Recover, answer on the bus, and warm the planner up in the background; plan
        only after :meth:`start`. Idempotent."""
        if self._warm_up is not None:
            return
        robot, kb, bus = self.context.robot, self.context.kb, self.context.bus
        recover(kb)  # before anything executes: the knowledge base only, fast
        if robot.problem is None or kb.objects() or kb.facts():
            self._seeded.set()
        self.planner = Planner(robot.planner.engine, robot.planner.timeout)
        self._relaying = True
        kb.add_listener(self._on_event)
        self._declared = [
            bus.subscribe(DIAGNOSES, self._on_diagnoses),
            bus.subscribe(EVENTS, self._on_bus_event),
        ]
        self._declared.extend(self._serve())
        self._stopping.clear()
        self._warm_up = threading.Thread(target=self._warm, name="high-level warm-up", daemon=True)
        self._warm_up.start()

    def _warm(self) -> None:
        """Load the domain in the planner worker, check the robot against it, seed the
        world, and start planning; or report why not."""
        from knowledge.validation import check_domain

        robot, kb = self.context.robot, self.context.kb
        try:
            self.planner.start()
            domain = self.planner.describe(robot.domain)
            world = None
            if robot.problem is not None:
                world = self.planner.read_world(robot.domain, robot.problem)
            objects = world.objects if world is not None else {}
            errors = [f for f in check_domain(robot, domain, objects) if f.is_error]
            if errors:
                raise ConfigError(str(errors[0]))
            if world is not None and robot.problem is not None:
                if not (kb.objects() or kb.facts()):
                    seed(kb, world, robot.problem)
                self._seeded.set()
            rules: list[IntegrityRule] = []
            for path in robot.integrity:
                rules.extend(read_rules(path, robot, domain, kb.objects()))
        except DuraError as e:
            if not self._stopping.is_set():
                self._fail(str(e))
            return
        except Exception as e:  # a bug: say so, rather than leave goals waiting
            if not self._stopping.is_set():
                log.exception("the high level's warm-up failed")
                self._fail(f"the planner's start failed: {type(e).__name__}: {e}")
            return
        while not self._begin.wait(0.1):  # the task executor starts meanwhile
            if self._stopping.is_set():
                return
        if self._stopping.is_set():
            return
        self.domain = domain
        runner = self.runner if isinstance(self.runner, TaskRunner) else self.runner()
        self.executor = PlanExecutor(
            kb, runner, robot.tasks, self._replan, self.limits, clock=self.clock
        )
        self._blocked = self.blocked()
        self.goals = GoalPlanner(kb, self.domain, self.planner, self.executor, blocked=self.blocked)
        with self._lock:  # the diagnoses that came meanwhile, then each as it comes
            self.integrity = IntegrityGoals(kb, self.domain, rules, clock=self.clock)
            if self._diagnoses:
                self.integrity.diagnosed(self._diagnoses)
            integrity = self._integrity_thread = threading.Thread(
                target=self._integrity_loop, name="integrity-goals", daemon=True
            )
        # started outside the lock: starting subscribes on the bus, whose callback
        # threads may be waiting for the lock (a diagnosis)
        integrity.start()
        self.executor.start()
        self.goals.start()
        self.sensing = Sensing(
            kb,
            self.domain,
            robot.sensing,
            subscribe=self._subscribe,
            changed=self._sensed,
            clock=self.clock,
        )
        self.sensing.start()
        self._running = [self.sensing.stop, self.goals.stop, self.executor.stop]
        self._ready.set()

    def wait_ready(self, timeout: float | None = None) -> bool:
        """Wait until the high level plans (the planner parsed the domain and
        :meth:`start` was called); whether it does. False also when it failed."""
        return self._ready.wait(timeout) and self._failure is None

    def _fail(self, reason: str) -> None:
        self._failure = reason
        self._ready.set()
        self._seeded.set()
        if self.on_failure is not None:
            self.on_failure(reason)
        else:
            log.error("the high level cannot start: %s", reason)

    def _planning(self) -> None:
        """Wait until goals can be planned (the planner parsed the domain).

        Raises:
            DuraError: the planner is not ready within WARM_UP_WAIT, or could not start.
        """
        if not self._ready.wait(WARM_UP_WAIT):
            raise DuraError(
                "the executive is still starting: its planner has not loaded the domain "
                f"within {WARM_UP_WAIT:g} s; try again"
            )
        if self._failure is not None:
            raise DuraError(f"the executive cannot plan: {self._failure}")

    def stop(self) -> None:
        if self._warm_up is None:
            return
        self._stopping.set()
        self._check.set()
        if self._warm_up.is_alive():
            self.planner.interrupt()  # the warm-up waits for the worker: end it now
        self._warm_up.join()
        self._warm_up = None
        self._begin.clear()
        with self._lock:
            thread, self._integrity_thread = self._integrity_thread, None
        if thread is not None and thread.ident is not None:  # it had started
            thread.join()
        for entity in self._declared:
            with contextlib.suppress(Exception):
                entity.undeclare()
        self._declared = []
        for stop in self._running:
            stop()
        self._running = []
        self.planner.close()
        self._relaying = False

    def _replan(self, reason: str) -> None:
        self.goals.replan(reason)

    def _subscribe(self, key: str, handler: Handler) -> Subscription:
        """Subscribe to a topic key where its messages are: a topic source, or the bus."""
        source = next((s for s in self.sources if s.serves(key)), None)
        if source is not None:
            return source.subscribe(key, handler)
        subscription: Subscription = self.context.bus.subscribe(key, handler)
        return subscription

    def _sensed(self, facts: list[Fact], reason: str) -> None:
        """A sensing rule changed facts: as a user's ``dura state set`` does."""
        self.executor.facts_changed([(f.name, f.args) for f in facts])
        self.goals.wake(reason)

    # --- events, diagnoses and integrity goals ---------------------------------------------

    def _on_event(self, event: Event) -> None:
        """An event this process logged: on the bus for all, then as any other."""
        if not self._relaying:
            return
        self.context.bus.publish(EVENTS, to_plain(event))
        self._followed(event.kind, event.subject)

    def _on_bus_event(self, message: Message) -> None:
        """An event another process logged (the task executor's, the repair rules' when
        they run apart): in the knowledge base already, to be followed here too."""
        if message.caller_id == self.context.bus.name or not self._relaying:
            return  # its own events, followed as they are logged
        payload = message.payload
        if not isinstance(payload, dict) or not isinstance(payload.get("kind"), str):
            log.warning("ignored a malformed event from %s", message.caller_id or "?")
            return
        self._followed(payload["kind"], str(payload.get("subject", "")))

    def _followed(self, kind: str, subject: str) -> None:
        if kind in FAULT_CHANGES:
            self._faults_changed.set()
        if self._started():  # until then, the goal planner's first round sees it all
            if kind in OUTSIDE_CHANGES:
                self.goals.world_changed(f"{kind} {subject}")
            elif kind in PLAN_CHANGES:
                self.goals.facts_changed(f"{kind} {subject}")
        if not kind.startswith("INTEGRITY_"):
            self._check.set()

    def _on_diagnoses(self, message: Any) -> None:
        try:
            payload = DiagnosisInfo.from_payload(message.payload).to_payload()
        except (KeyError, ValueError, TypeError) as e:
            log.warning("ignored a malformed diagnosis on %s: %s", message.key, e)
            return
        with self._lock:
            self._diagnoses = payload
            if self._integrity_thread is not None:
                self.integrity.diagnosed(payload)
        self._check.set()

    def _integrity_loop(self) -> None:
        """Check the integrity rules when something changed, and when a rule is due."""
        while not self._stopping.is_set():
            due = self.integrity.next_check()
            wait = None if due is None else max(0.0, self.clock.wall(due - self.clock.monotonic()))
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

    def _serve(self) -> list[Any]:
        """Answer every verb of :mod:`executive.bus.api.planning`; returns the queryables."""
        bus = self.context.bus
        return [
            api.GOAL_ADD.serve(bus, self._goal_add),
            api.GOAL_LIST.serve(bus, self._goal_list),
            api.GOAL_SHOW.serve(bus, self._goal_show),
            api.GOAL_CANCEL.serve(bus, self._goal_cancel),
            api.PLAN_SHOW.serve(bus, self._plan_show),
            api.PLAN_DRY_RUN.serve(bus, self._plan_dry_run),
            api.STATE_GET.serve(bus, self._state_get),
            api.STATE_SET.serve(bus, lambda r: self._state_change(r, unset=False)),
            api.STATE_UNSET.serve(bus, lambda r: self._state_change(r, unset=True)),
            api.OBJECT_ADD.serve(bus, self._object_add),
            api.OBJECT_REMOVE.serve(bus, self._object_remove),
            api.DOMAIN_SHOW.serve(bus, self._domain_show),
            api.EVENTS.serve(bus, self._events),
            api.STATUS.serve(bus, self._status),
        ]

    def _goal_add(self, request: api.GoalAdd) -> api.GoalReply:
        self._planning()
        goal = submit(
            self.context.kb,
            self.domain,
            request.expression,
            priority=request.priority,
            deadline=request.deadline,
            source=request.source,
            keep=request.keep,
        )
        self.goals.wake(f"goal {goal.id} added")
        return api.GoalReply(to_plain(goal))

    def _goal_list(self, request: api.GoalQuery) -> api.GoalsReply:
        return api.GoalsReply(to_plain(self.context.kb.goals(request.states)))

    def _goal_show(self, request: api.GoalId) -> api.GoalHistory:
        kb = self.context.kb
        goal = kb.goal(request.id)
        subject = f"goal {goal.id}"
        events = [e for e in kb.events() if e.subject == subject or _names_goal(e, goal.id)]
        return api.GoalHistory(to_plain(goal), to_plain(events))

    def _goal_cancel(self, request: api.GoalId) -> api.GoalReply:
        """Cancelled by the goal planner's thread, which owns goal states; the reply is
        the goal as it left that thread (or the reason it could not be cancelled)."""
        self._planning()
        return api.GoalReply(to_plain(self.goals.cancel(request.id)))

    def _plan_show(self, request: Empty) -> api.PlanReply:
        plan = self.context.kb.latest_plan()
        return api.PlanReply(None if plan is None else to_plain(plan), self._execution())

    def _plan_dry_run(self, request: api.DryRun) -> api.DryRunReply:
        """Plan for the open goals and those asked about on the live state; nothing
        changes."""
        self._planning()
        return dry_run(
            self.context.kb,
            self.domain,
            self.planner,
            self.executor.planning_facts(),
            self.blocked(),
            clock=self.clock,
            timeout=request.timeout,
            asked=request.goals,
        )

    def _state_get(self, request: api.StateQuery) -> api.StateReply:
        self._seeded.wait(WARM_UP_WAIT)  # a new robot's world comes with its domain
        kb = self.context.kb
        words = request.pattern.strip("() ").split()
        facts = [f for f in kb.facts() if _matches(words, f.name, f.args)]
        return api.StateReply([_fact(f) for f in facts], kb.objects())

    def _state_change(self, request: api.FactChange, *, unset: bool) -> api.FactReply:
        self._planning()
        kb = self.context.kb
        fact = parse_fact(request.fact, Signature.of(self.domain, kb.objects()))
        with kb.transaction():
            if unset or fact.value is False:
                kb.update_facts(remove=[fact])
            else:
                kb.set_fact(fact)
            kind = "STATE_UNSET" if unset else "STATE_SET"
            kb.log_event(kind, str(fact), {"source": request.source})
        self.executor.facts_changed([(fact.name, fact.args)])
        by = "the user" if request.source == "user" else request.source
        self.goals.wake(f"{fact} {'unset' if unset else 'set'} by {by}")
        return api.FactReply(_fact(fact))

    def _object_add(self, request: api.ObjectAdd) -> api.ObjectAdd:
        self._planning()
        name, type_name = request.name, request.type
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
        return api.ObjectAdd(name, type_name)

    def _object_remove(self, request: api.ObjectName) -> api.StateReply:
        """Remove an object and every fact that names it (as PlanSys2 removes an
        instance); refused, with who names it, while an open goal, the current plan or an
        integrity rule does."""
        self._planning()
        name, kb = request.name, self.context.kb
        with kb.transaction():
            objects = kb.objects()
            if name not in objects:
                raise KnowledgeError(f"no object '{name}'{did_you_mean(name, sorted(objects))}")
            users = self._naming(name)
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
        self.executor.facts_changed()
        self.goals.wake(f"object {name} removed by the user")
        return api.StateReply([_fact(f) for f in facts], {name: objects[name]})

    def _naming(self, name: str) -> list[str]:
        """Who names an object: open goals, the current plan's steps, integrity rules."""
        kb = self.context.kb
        users = [
            f"goal {g.id} {g.expression} is {g.state.value}"
            for g in kb.open_goals()
            if _mentions(g.expression, name)
        ]
        plan = kb.latest_plan()
        if plan is not None and plan.state in (PlanState.PENDING, PlanState.EXECUTING):
            steps = [f"{s.action}({', '.join(s.args)})" for s in plan.steps if name in s.args]
            if steps:
                users.append(f"plan {plan.id} ({plan.state.value}) has {', '.join(steps)}")
        for rule in self.integrity.rules:
            condition = rule.subject if rule.trigger is Trigger.CONDITION else ""
            if _mentions(rule.goal, name) or _mentions(condition, name):
                users.append(f"integrity rule '{rule.name}' ({rule.where})")
        return users

    def _domain_show(self, request: Empty) -> api.DomainReply:
        self._planning()
        return describe(self.domain, self.context.robot, self.blocked())

    def _events(self, request: api.EventQuery) -> api.EventsReply:
        events = self.context.kb.events(
            after=request.after,
            kind=request.kind,
            limit=min(request.limit, MAX_EVENTS),
            oldest=request.oldest,
        )
        return api.EventsReply(to_plain(events))

    def _status(self, request: Empty) -> api.StatusReply:
        kb = self.context.kb
        plan = kb.latest_plan()
        return api.StatusReply(
            robot=self.context.robot.name,
            goals=to_plain(kb.goals()),
            plan=None if plan is None else to_plain(plan),
            execution=self._execution(),
            diagnoses=self._diagnoses,
            faults=to_plain([c for c in kb.components() if c.fault_count or c.permanent_fault]),
            tasks=self._section("tasks"),
            components=self._section("components"),
            planning=self.goals.status() if self._started() else _STARTING,
        )

    def _started(self) -> bool:
        return self._ready.is_set() and self._failure is None

    def _execution(self) -> dict[str, Any]:
        return self.executor.status() if self._started() else dict(to_plain(ExecutionStatus()))

    def _section(self, name: str) -> Any:
        """A section another service adds to ``status``; its error if it did not answer."""
        section = self.extra_status.get(name)
        if section is None:
            return None
        try:
            return section()
        except DuraError as e:
            return {"error": str(e)}


_STARTING = to_plain(PlannerStatus(starting=True))  # the planner is warming up


def _names_goal(event: Event, goal_id: int) -> bool:
    goals = event.data.get("goals") if isinstance(event.data, dict) else None
    return isinstance(goals, list) and goal_id in goals


_TOKEN = re.compile(r"[()]|[^\s()]+")


def _mentions(expression: str, name: str) -> bool:
    """Whether a PDDL expression names an object: as an argument, not as the name of a
    predicate, function or connective (the word after an opening parenthesis)."""
    tokens = _TOKEN.findall(expression)
    return any(t == name and (i == 0 or tokens[i - 1] != "(") for i, t in enumerate(tokens))


def _matches(words: list[str], name: str, args: tuple[str, ...]) -> bool:
    """``robot_at``, ``(robot_at lab)``, ``(robot_at *)``: a name and leading arguments."""
    if not words:
        return True
    if words[0] not in ("*", name):
        return False
    return all(w in ("*", a) for w, a in zip(words[1:], args, strict=False))


def _fact(fact: Fact) -> dict[str, Any]:
    return {"name": fact.name, "args": list(fact.args), "value": fact.value, "text": str(fact)}
