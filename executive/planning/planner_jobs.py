"""The jobs of the planner's worker process, with unified-planning: build the problem
(:mod:`executive.planning.problem`), solve it, validate the plan with a UP validator and
turn it into the executable partial order (:mod:`executive.planning.stn`).

:class:`PlannerJobs` keeps unified-planning's environment, the engines, the validators
and the parsed domains warm between jobs; :mod:`executive.planning.planner_worker`
answers each message with one of its methods. Engines' own output goes to a file whose
last lines join a failed result's log. Results are the planner module's types
(:class:`~executive.planning.planner.PlanResult`), so the client unpickles them as its
own. Only the worker process imports this module, after
:func:`executive.fast_start.import_unified_planning`.
"""

from __future__ import annotations

import os
import sys
import warnings
from collections.abc import Callable
from dataclasses import replace
from pathlib import Path
from typing import Any

import up_kairos
from unified_planning.engines import ValidationResultStatus
from unified_planning.engines.mixins import AnytimePlannerMixin
from unified_planning.environment import get_environment
from unified_planning.shortcuts import AnytimePlanner, OneshotPlanner, PlanValidator

from executive.planning.engine_choice import choose
from executive.planning.metric import TOTAL_COST, costs_problem
from executive.planning.planner import (
    SEARCHED,
    SEARCHING,
    PlanningTask,
    PlanResult,
    PlanStatus,
    engine_names,
    plugins,
)
from executive.planning.problem import World, build, frozen, read_world
from executive.planning.reachability import missing_atoms
from executive.planning.stn import partial_order
from knowledge.description import AUTO
from knowledge.domain import DomainInfo, describe, parse, parse_problem
from knowledge.errors import DomainError, DuraError, PlanningError

_LOG_TAIL = 40  # lines of engine output kept in a result


def _capturing_output(method: Any) -> Any:
    """Run a worker method with the engines' output (fd 1 and 2) going to a file, and put
    the file's last lines into the result's log."""

    def wrapped(self: PlannerJobs, *args: Any) -> PlanResult:
        sys.stdout.flush()
        sys.stderr.flush()
        saved = [os.dup(1), os.dup(2)]
        with open(self.output, "w+b") as capture:
            os.dup2(capture.fileno(), 1)
            os.dup2(capture.fileno(), 2)
            try:
                res: PlanResult = method(self, *args)
            finally:
                sys.stdout.flush()
                sys.stderr.flush()
                os.dup2(saved[0], 1)
                os.dup2(saved[1], 2)
                for fd in saved:
                    os.close(fd)
            capture.seek(0)
            output = capture.read().decode(errors="replace").splitlines()
        tail = tuple(line for line in output[-_LOG_TAIL:] if line.strip())
        return replace(res, log=tail + res.log) if res.status is not PlanStatus.SOLVED else res

    return wrapped


# How to install the engines that are optional extras.
INSTALL = {"tamer": " (it is an optional extra: pip install 'dura[tamer]', or -e '.[tamer]')"}


class PlannerJobs:
    """A planner worker's jobs (:meth:`prepare`, :meth:`describe`, :meth:`world`,
    :meth:`solve`), with unified-planning's environment, engines, validators and parsed
    domains kept warm between them."""

    def __init__(self, output: Path) -> None:
        """Make unified-planning's environment with Kairos and the installed planner
        plugins; ``output``: the file the engines' own output goes to during a job."""
        self.output = output
        self.engines: dict[str, Any] = {}
        self.validators: dict[str, Any] = {}
        self.anytime: dict[str, Any] = {}  # engines in anytime mode, for problems with a metric
        self.progress: Callable[[str], None] = lambda phase: None  # told of a solve's phases
        self.domains: dict[tuple[Path, bool], tuple[float, Any]] = {}
        warnings.simplefilter("ignore")  # UP warns about what it cannot establish; we check
        self.env = get_environment()
        self.env.credits_stream = None
        up_kairos.register(self.env)
        for name, ep in plugins().items():
            if name in self.env.factory.engines:
                continue
            module, _, attr = ep.value.partition(":")
            try:
                self.env.factory.add_engine(name, module, attr)
            except Exception as e:
                print(f"planner plugin '{name}' ({ep.value}) failed to load: {e}", file=sys.stderr)

    def domain(self, path: Path, costs: bool = False) -> Any:
        """A parsed domain, kept while its file is unchanged; with ``costs``, with its
        ``total-cost`` increases compiled into action costs (as UP's reader does for a
        problem whose metric is ``(total-cost)``).

        Raises:
            DomainError: the file is not a valid domain, or has no action costs.
        """
        mtime = path.stat().st_mtime
        cached = self.domains.get((path, costs))
        if cached is None or cached[0] != mtime:
            parsed = self.domain(path) if costs else parse(path)
            if costs:
                if not parsed.has_fluent(TOTAL_COST.name):
                    raise DomainError(f"{path}: the metric needs the function (total-cost)")
                parsed = parse_problem(path, costs_problem(parsed.name), domain_checked=True)
            cached = (mtime, parsed)
            self.domains[(path, costs)] = cached
        return cached[1]

    def engine(self, name: str) -> Any:
        if name not in self.engines:
            if name not in self.env.factory.engines:
                hint = INSTALL.get(name, "")
                raise PlanningError(f"engine '{name}' is not installed{hint}")
            self.engines[name] = OneshotPlanner(name=name)
        return self.engines[name]

    def available(self) -> dict[str, Any]:
        """Every installed engine dura may choose, in dura's order, by name → its class."""
        known = self.env.factory.engines
        return {n: self.env.factory.engine(n) for n in engine_names() if n in known}

    def installed(self, engine: str) -> list[str]:
        """The names of :meth:`available`."""
        return list(self.available())

    def best(self, name: str, problem: Any, timeout: float) -> Any:
        """The last (best) plan an anytime engine finds by the timeout, as its result;
        without one, its last answer."""
        if name not in self.anytime:
            self.anytime[name] = AnytimePlanner(name=name)
        last = None
        for answer in self.anytime[name].get_solutions(problem, timeout=timeout):
            if answer.plan is not None or last is None or last.plan is None:
                last = answer
        if last is None:
            raise PlanningError(f"{name} gave no answer")
        return last

    def validator(self, name: str) -> Any:
        """A plan validator by name, kept (UP's factory looks up credits on every call)."""
        if name not in self.validators:
            self.validators[name] = PlanValidator(name=name)
        return self.validators[name]

    def prepare(self, engine: str, domain: Path) -> bool:
        self.domain(domain)
        if engine != AUTO:
            self.engine(engine)
        return True

    def describe(self, engine: str, domain: Path) -> DomainInfo:
        """Parse a domain (and load the engine): the signatures the executive checks
        goals, facts and tasks against, so that it needs no unified-planning itself."""
        self.prepare(engine, domain)
        return describe(self.domain(domain), domain)

    def world(self, engine: str, domain: Path, problem: Path) -> World:
        """The objects and facts of a problem file of the domain."""
        return read_world(domain, problem, self.domain(domain))[0]

    @_capturing_output
    def solve(self, engine_name: str, task: PlanningTask, timeout: float) -> PlanResult:
        """Plan with an engine (``auto``: the first installed one that supports the
        problem), validate the plan and make it a partial order."""
        notes: list[str] = []

        def result(status: PlanStatus, *lines: str, **more: Any) -> PlanResult:
            return PlanResult(status, more.get("plan"), engine_name, lines, 0.0,
                              more.get("validator", ""), more.get("missing", ()),
                              tuple(notes))  # fmt: skip

        metric = task.metric
        try:
            costs = metric is not None and metric.expression == TOTAL_COST
            domain = self.domain(task.domain, costs)
            problem = frozen(build(domain, task.world, task.goals, task.blocked, metric))
            if engine_name != AUTO:
                self.engine(engine_name)  # not installed: say how to install it
        except DuraError as e:
            return result(PlanStatus.ERROR, str(e))
        available = self.available()
        wanted = list(available) if engine_name == AUTO else [engine_name]
        choice = choose(wanted, available, problem.kind.features)
        if choice.refusal:
            return result(PlanStatus.UNSUPPORTED, choice.refusal)
        engine_name = choice.engine
        engine = self.engine(engine_name)
        if choice.unoptimised:
            notes.append(choice.unoptimised)
            problem = frozen(build(domain, task.world, task.goals, task.blocked))
        self.progress(SEARCHING)  # the hard timeout counts from here
        try:
            if problem.quality_metrics and issubclass(type(engine), AnytimePlannerMixin):
                answer = self.best(engine_name, problem, timeout)
            else:
                answer = engine.solve(problem, timeout=timeout)
        except Exception as e:  # an engine's own failure is a result, not a crash
            return result(PlanStatus.ERROR, f"{type(e).__name__}: {e}")
        self.progress(SEARCHED)
        lines = [str(m.message).splitlines()[0] for m in answer.log_messages or () if m.message]
        status = _status(answer.status.name)
        if answer.plan is not None and status is PlanStatus.TIMEOUT:
            status = PlanStatus.SOLVED  # the best plan found by the timeout
        if answer.plan is None or status is not PlanStatus.SOLVED:
            why = _missing(problem, task) if status in _EXPLAINED else ()
            status = PlanStatus.ERROR if status is PlanStatus.SOLVED else status
            return result(status, *lines, missing=why)
        valid, validator, reason = _validate(problem, answer.plan, self.validator)
        if not valid:
            return result(PlanStatus.INVALID_PLAN, *lines, reason, validator=validator)
        try:
            plan = partial_order(problem, answer.plan)
        except DuraError as e:
            return result(PlanStatus.ERROR, *lines, str(e))
        return result(PlanStatus.SOLVED, *lines, plan=plan, validator=validator)


_EXPLAINED = (PlanStatus.UNSOLVABLE, PlanStatus.NOT_FOUND, PlanStatus.TIMEOUT)


def _missing(problem: Any, task: PlanningTask) -> tuple[str, ...]:
    """The goal atoms no action can make true from the task's world (relaxed)."""
    try:
        return missing_atoms(problem, [g.expression for g in task.goals])
    except Exception as e:  # an explanation must never cost the result
        return (f"(reachability not checked: {type(e).__name__}: {e})",)


def _status(name: str) -> PlanStatus:
    return {
        "SOLVED_SATISFICING": PlanStatus.SOLVED,
        "SOLVED_OPTIMALLY": PlanStatus.SOLVED,
        "INTERMEDIATE": PlanStatus.SOLVED,
        "UNSOLVABLE_PROVEN": PlanStatus.UNSOLVABLE,
        "UNSOLVABLE_INCOMPLETELY": PlanStatus.NOT_FOUND,
        "TIMEOUT": PlanStatus.TIMEOUT,
        "UNSUPPORTED_PROBLEM": PlanStatus.UNSUPPORTED,
    }.get(name, PlanStatus.ERROR)


_VALIDATORS = {
    "TimeTriggeredPlan": ("up_time_triggered_validator", "kairos-val"),
    "SequentialPlan": ("sequential_plan_validator", "kairos-val"),
}


def _validate(problem: Any, plan: Any, validator: Callable[[str], Any]) -> tuple[bool, str, str]:
    """Check a plan with the first UP validator that supports the problem (UP's own
    before Kairos', so that a Kairos plan gets an independent check).

    Returns (valid, validator name, reason if invalid).
    """
    names = _VALIDATORS.get(type(plan).__name__, ())
    if not names:
        return False, "", f"no validator for a {type(plan).__name__}"
    chosen = next((n for n in names if validator(n).supports(problem.kind)), names[0])
    try:
        answer = validator(chosen).validate(problem, plan)
    except NotImplementedError:  # UP's simulator cannot evaluate some metrics (makespan of
        # a sequential plan): the plan's validity does not depend on its metric
        plain = problem.clone()
        plain.clear_quality_metrics()
        answer = validator(chosen).validate(plain, plan)
    if answer.status == ValidationResultStatus.VALID:
        return True, chosen, ""
    messages = [str(m.message).splitlines()[0] for m in answer.log_messages or ()]
    reason = answer.reason.name.lower() if answer.reason is not None else "unknown"
    return False, chosen, f"{chosen}: {reason} {'; '.join(messages)}".strip()
