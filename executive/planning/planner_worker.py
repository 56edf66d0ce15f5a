"""The planner's worker process: unified-planning and its engines, kept warm.

:class:`~executive.planning.planner.Planner` starts it as ``python -m
executive.planning.planner_worker`` in its own process group and temporary folder and
sends it one job at a time over stdin/stdout (pickled frames, see
:func:`~executive.planning.planner.send_frame`): build the problem
(:mod:`executive.planning.problem`), solve it, validate the plan with a UP validator and
turn it into the executable partial order (:mod:`executive.planning.stn`). Engines'
own output goes to a file whose last lines join a failed result's log. Results are the
planner module's types (:class:`~executive.planning.planner.PlanResult`), so the
client unpickles them as its own.
"""

from __future__ import annotations

import contextlib
import os
import shutil
import sys
import tempfile
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import IO, TYPE_CHECKING, Any

from executive.planning.planner import (
    TMP_PREFIX,
    PlanningTask,
    PlanResult,
    PlanStatus,
    plugins,
    receive_frame,
    send_frame,
)
from knowledge.errors import DuraError, PlanningError

if TYPE_CHECKING:
    from executive.planning.problem import World
    from knowledge.domain import DomainInfo

_LOG_TAIL = 40  # lines of engine output kept in a result


def _capturing_output(method: Any) -> Any:
    """Run a worker method with the engines' output (fd 1 and 2) going to a file, and put
    the file's last lines into the result's log."""

    def wrapped(self: _Worker, *args: Any) -> PlanResult:
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


@dataclass
class _Worker:
    """The worker's state: UP's environment, engines and parsed domains, kept warm."""

    output: Path
    engines: dict[str, Any] = field(default_factory=dict)
    validators: dict[str, Any] = field(default_factory=dict)
    domains: dict[Path, tuple[float, Any]] = field(default_factory=dict)
    env: Any = None

    def setup(self) -> None:
        import warnings

        from executive import fast_start

        fast_start.import_unified_planning()  # before anything else imports it
        from unified_planning.environment import get_environment

        warnings.simplefilter("ignore")  # UP warns about what it cannot establish; we check
        self.env = get_environment()
        self.env.credits_stream = None
        import up_kairos

        up_kairos.register(self.env)
        for name, ep in plugins().items():
            if name in self.env.factory.engines:
                continue
            module, _, attr = ep.value.partition(":")
            try:
                self.env.factory.add_engine(name, module, attr)
            except Exception as e:
                print(f"planner plugin '{name}' ({ep.value}) failed to load: {e}", file=sys.stderr)

    def domain(self, path: Path) -> Any:
        from knowledge.domain import parse

        mtime = path.stat().st_mtime
        cached = self.domains.get(path)
        if cached is None or cached[0] != mtime:
            cached = (mtime, parse(path))
            self.domains[path] = cached
        return cached[1]

    def engine(self, name: str) -> Any:
        if name not in self.engines:
            from unified_planning.shortcuts import OneshotPlanner

            if name not in self.env.factory.engines:
                hint = INSTALL.get(name, "")
                raise PlanningError(f"engine '{name}' is not installed{hint}")
            self.engines[name] = OneshotPlanner(name=name)
        return self.engines[name]

    def validator(self, name: str) -> Any:
        """A plan validator by name, kept (UP's factory looks up credits on every call)."""
        if name not in self.validators:
            from unified_planning.shortcuts import PlanValidator

            self.validators[name] = PlanValidator(name=name)
        return self.validators[name]

    def prepare(self, engine: str, domain: Path) -> bool:
        self.domain(domain)
        self.engine(engine)
        return True

    def describe(self, engine: str, domain: Path) -> DomainInfo:
        """Parse a domain (and load the engine): the signatures the executive checks
        goals, facts and tasks against, so that it needs no unified-planning itself."""
        from knowledge.domain import describe

        self.prepare(engine, domain)
        return describe(self.domain(domain), domain)

    def world(self, engine: str, domain: Path, problem: Path) -> World:
        """The objects and facts of a problem file of the domain."""
        from executive.planning.problem import read_world

        return read_world(domain, problem, self.domain(domain))[0]

    @_capturing_output
    def solve(self, engine_name: str, task: PlanningTask, timeout: float) -> PlanResult:
        from executive.planning.problem import build, frozen

        def result(status: PlanStatus, *lines: str, **more: Any) -> PlanResult:
            return PlanResult(status, more.get("plan"), engine_name, tuple(lines), 0.0,
                              more.get("validator", ""), more.get("missing", ()))  # fmt: skip

        try:
            problem = frozen(build(self.domain(task.domain), task.world, task.goals, task.blocked))
            engine = self.engine(engine_name)
        except DuraError as e:
            return result(PlanStatus.ERROR, str(e))
        unsupported = _missing_features(engine, problem)
        if unsupported:
            return result(PlanStatus.UNSUPPORTED, f"unsupported features: {unsupported}")
        try:
            answer = engine.solve(problem, timeout=timeout)
        except Exception as e:  # an engine's own failure is a result, not a crash
            return result(PlanStatus.ERROR, f"{type(e).__name__}: {e}")
        lines = [str(m.message).splitlines()[0] for m in answer.log_messages or () if m.message]
        status = _status(answer.status.name)
        if answer.plan is None or status is not PlanStatus.SOLVED:
            why = _missing(problem, task) if status in _EXPLAINED else ()
            status = PlanStatus.ERROR if status is PlanStatus.SOLVED else status
            return result(status, *lines, missing=why)
        valid, validator, reason = _validate(problem, answer.plan, self.validator)
        if not valid:
            return result(PlanStatus.INVALID_PLAN, *lines, reason, validator=validator)
        from executive.planning.stn import partial_order

        try:
            plan = partial_order(problem, answer.plan)
        except DuraError as e:
            return result(PlanStatus.ERROR, *lines, str(e))
        return result(PlanStatus.SOLVED, *lines, plan=plan, validator=validator)


_EXPLAINED = (PlanStatus.UNSOLVABLE, PlanStatus.NOT_FOUND, PlanStatus.TIMEOUT)


def _missing(problem: Any, task: PlanningTask) -> tuple[str, ...]:
    """The goal atoms no action can make true from the task's world (relaxed)."""
    from executive.planning.reachability import missing_atoms

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


def _missing_features(engine: Any, problem: Any) -> str:
    """The features of a problem an engine declares it does not support ('' if none)."""
    supported = engine.supported_kind().features
    missing = sorted(f.lower() for f in problem.kind.features if f not in supported)
    return ", ".join(missing)


_VALIDATORS = {
    "TimeTriggeredPlan": ("up_time_triggered_validator", "kairos-val"),
    "SequentialPlan": ("sequential_plan_validator", "kairos-val"),
}


def _validate(problem: Any, plan: Any, validator: Callable[[str], Any]) -> tuple[bool, str, str]:
    """Check a plan with the first UP validator that supports the problem (UP's own
    before Kairos', so that a Kairos plan gets an independent check).

    Returns (valid, validator name, reason if invalid).
    """
    from unified_planning.engines import ValidationResultStatus

    names = _VALIDATORS.get(type(plan).__name__, ())
    if not names:
        return False, "", f"no validator for a {type(plan).__name__}"
    chosen = next((n for n in names if validator(n).supports(problem.kind)), names[0])
    answer = validator(chosen).validate(problem, plan)
    if answer.status == ValidationResultStatus.VALID:
        return True, chosen, ""
    messages = [str(m.message).splitlines()[0] for m in answer.log_messages or ()]
    reason = answer.reason.name.lower() if answer.reason is not None else "unknown"
    return False, chosen, f"{chosen}: {reason} {'; '.join(messages)}".strip()


def _frames(stream: IO[bytes]) -> Iterator[Any]:
    while True:
        try:
            yield receive_frame(stream, None)
        except EOFError:
            return


def serve() -> None:
    """The worker's main loop: answer messages on stdin until it closes."""
    protocol_in = os.fdopen(os.dup(0), "rb")
    protocol_out = os.fdopen(os.dup(1), "wb")
    devnull = os.open(os.devnull, os.O_RDWR)
    os.dup2(devnull, 0)
    os.dup2(2, 1)  # stray prints go to the worker log, never into the protocol
    try:
        worker = _Worker(Path(tempfile.gettempdir()) / "engine-output.txt")
        worker.setup()
        with contextlib.suppress(BrokenPipeError):  # dura died while the worker worked
            send_frame(protocol_out, "ready")
            for message in _frames(protocol_in):
                kind, engine, *args = message
                try:
                    answer = getattr(worker, kind)(engine, *args)
                except DuraError as e:  # a planning job's failure is a result; others raise
                    answer = (
                        PlanResult(PlanStatus.ERROR, None, engine, (str(e),))
                        if kind == "solve"
                        else e
                    )
                send_frame(protocol_out, answer)
    finally:
        # the input closed or the output broke: dura is done with this worker, or died
        # without cleaning up (SIGKILL), also while the worker still warmed up; either
        # way the engines' temporary files go with it
        own = Path(tempfile.gettempdir())
        if own.name.startswith(TMP_PREFIX):
            shutil.rmtree(own, ignore_errors=True)


if __name__ == "__main__":
    serve()
