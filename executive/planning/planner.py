"""The one adapter to unified-planning's engines: every engine in a worker process.

:class:`Planner` keeps a warm worker process (``python -m executive.planning.planner``) that
has unified-planning and the engine loaded, and sends it one job at a time: build the
problem (:mod:`executive.planning.problem`), solve it, validate the plan with a UP validator,
and turn it into the executable partial order (:mod:`executive.planning.stn`). The worker runs
in its own process group, under a hard timeout: when a job runs past the engine's
timeout plus a grace period (TAMER ignores timeouts), the whole group is killed (the
Aries and Fast Downward binaries with it) and a new worker is started for the next
job. The worker's temp dir is private (Aries leaves files behind) and removed with it.

Engines: ``kairos`` (default, up-kairos), ``aries``, ``fast-downward`` (classical
domains), ``tamer`` (the optional ``tamer`` extra), and plugins: a UP engine class
registered under the entry-point group ``dura.planners`` (``name = "pkg.mod:Engine"``).
"""

from __future__ import annotations

import contextlib
import enum
import logging
import os
import pickle  # nosec: only between dura and its own worker process
import select
import shutil
import signal
import struct
import subprocess
import sys
import tempfile
import threading
import time
from collections.abc import Iterator
from dataclasses import dataclass, field, replace
from importlib import metadata
from pathlib import Path
from typing import IO, Any

import psutil

from executive.planning.goals import GoalSpec
from executive.planning.partial_order import PartialOrderPlan
from executive.planning.problem import World
from knowledge.description import DEFAULT_ENGINE
from knowledge.errors import DuraError, PlanningError

log = logging.getLogger("dura.planner")

BUILTIN_ENGINES = ("kairos", "aries", "fast-downward", "tamer")
PLUGIN_GROUP = "dura.planners"
TMP_PREFIX = "dura-planner-"  # the worker's temporary folder (engines write there)
WORKER_PID = "worker.pid"  # in that folder: whose it is
ABANDONED = 3600.0  # seconds after which a folder without a worker pid is left over
STARTUP_TIMEOUT = 120.0  # seconds for a worker to import unified-planning and the engines
_HEADER = struct.Struct("!Q")
_LOG_TAIL = 40  # lines of engine output kept in a result


class PlanStatus(enum.Enum):
    SOLVED = "solved"
    UNSOLVABLE = "unsolvable"  # the engine proved that no plan exists
    NOT_FOUND = "not_found"  # the engine gave up without a proof
    TIMEOUT = "timeout"
    UNSUPPORTED = "unsupported"  # the engine cannot handle this kind of problem
    INVALID_PLAN = "invalid_plan"  # the validator rejected the engine's plan
    ERROR = "error"

    @property
    def no_plan(self) -> bool:
        """The engine answered that it has no plan (not: it could not answer)."""
        return self in (PlanStatus.UNSOLVABLE, PlanStatus.NOT_FOUND)


@dataclass(frozen=True)
class PlanningTask:
    """What to plan: a domain file, a world to start from and the goals to reach,
    without the ``blocked`` actions (the robot cannot do them now)."""

    domain: Path
    world: World
    goals: tuple[GoalSpec, ...]
    blocked: frozenset[str] = frozenset()


@dataclass(frozen=True)
class PlanResult:
    """The outcome of one planning call; ``plan`` is set when ``status`` is SOLVED."""

    status: PlanStatus
    plan: PartialOrderPlan | None
    engine: str
    log: tuple[str, ...] = ()
    time: float = 0.0  # seconds, from sending the job to receiving the answer
    validator: str = ""  # the UP validator that accepted the plan

    @property
    def ok(self) -> bool:
        return self.status is PlanStatus.SOLVED

    @property
    def reason(self) -> str:
        """One line on why there is no plan (empty when solved)."""
        if self.ok:
            return ""
        last = next((line for line in reversed(self.log) if line.strip()), "")
        text = _REASONS[self.status].format(engine=self.engine)
        return f"{text}: {last}" if last and self.status not in _QUIET else text


_REASONS = {
    PlanStatus.UNSOLVABLE: "{engine} proved that no plan exists",
    PlanStatus.NOT_FOUND: "{engine} found no plan",
    PlanStatus.TIMEOUT: "{engine} found no plan in time",
    PlanStatus.UNSUPPORTED: "{engine} cannot plan for this problem",
    PlanStatus.INVALID_PLAN: "the plan of {engine} failed validation",
    PlanStatus.ERROR: "{engine} failed",
}
_QUIET = (PlanStatus.UNSOLVABLE, PlanStatus.NOT_FOUND)


def plugins() -> dict[str, metadata.EntryPoint]:
    """Planner plugins by name (entry-point group ``dura.planners``), not loaded."""
    return {ep.name: ep for ep in metadata.entry_points(group=PLUGIN_GROUP)}


def engine_names() -> list[str]:
    """Every engine name a robot description may choose."""
    return [*BUILTIN_ENGINES, *sorted(set(plugins()) - set(BUILTIN_ENGINES))]


def hard_timeout(timeout: float) -> float:
    """When a job is killed: the engine's timeout plus time to build, validate and convert."""
    return timeout + max(2.0, timeout / 4)


class Planner:
    """One engine in a warm worker process; :meth:`solve` is safe to call from any thread.

    Args:
        engine: an engine name (see :func:`engine_names`).
        timeout: seconds the engine may search; the job is killed a little later.
    """

    def __init__(self, engine: str = DEFAULT_ENGINE, timeout: float = 30.0) -> None:
        if engine not in engine_names():
            raise PlanningError(
                f"unknown planner engine '{engine}' (choose from {', '.join(engine_names())})"
            )
        if timeout <= 0:
            raise PlanningError(f"the planner timeout must be positive, not {timeout:g}")
        self.engine = engine
        self.timeout = timeout
        self._lock = threading.Lock()
        self._process: subprocess.Popen[bytes] | None = None
        self._tmp: Path | None = None
        self._ready = False

    def __enter__(self) -> Planner:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    # --- the worker ---------------------------------------------------------------------

    def start(self, domain: Path | None = None) -> None:
        """Start the worker now (and parse ``domain`` in it), so the first job is fast."""
        with self._lock:
            self._spawn()
            if domain is not None:
                self._call(("prepare", self.engine, Path(domain)), STARTUP_TIMEOUT)

    def _spawn(self) -> None:
        if self._process is not None and self._process.poll() is None:
            return
        self._reap()
        _sweep(Path(tempfile.gettempdir()))
        self._tmp = Path(tempfile.mkdtemp(prefix=TMP_PREFIX))
        root = str(Path(__file__).resolve().parents[2])
        path = os.pathsep.join(p for p in (root, os.environ.get("PYTHONPATH", "")) if p)
        env = {**os.environ, "TMPDIR": str(self._tmp), "PYTHONPATH": path}
        with open(self._tmp / "worker.log", "wb") as stderr:
            self._process = subprocess.Popen(
                [sys.executable, "-m", "executive.planning.planner"],
                stdin=subprocess.PIPE,
                stdout=subprocess.PIPE,
                stderr=stderr,
                env=env,
                start_new_session=True,  # its own process group, killed as a whole
            )
        (self._tmp / WORKER_PID).write_text(str(self._process.pid))
        self._ready = False

    def _reap(self) -> None:
        """Kill the worker's process group, wait for it, remove its temp dir."""
        process, self._process = self._process, None
        if process is not None:
            with _suppress_lookup():  # the group also holds the engines' own processes
                os.killpg(process.pid, signal.SIGKILL)
            process.wait()
            for stream in (process.stdin, process.stdout):
                if stream is not None:
                    stream.close()
        if self._tmp is not None:
            shutil.rmtree(self._tmp, ignore_errors=True)
            self._tmp = None

    def close(self) -> None:
        """Stop the worker (it exits when its input closes; killed if it does not)."""
        with self._lock:
            process = self._process
            if process is not None and process.stdin is not None and process.poll() is None:
                try:
                    process.stdin.close()
                    process.wait(timeout=2.0)
                except (OSError, subprocess.TimeoutExpired):
                    pass
            self._reap()

    def _worker_log(self) -> str:
        if self._tmp is None:
            return ""
        try:
            lines = (self._tmp / "worker.log").read_text(errors="replace").splitlines()
        except OSError:
            return ""
        return next((line for line in reversed(lines) if line.strip()), "")

    def _wait_ready(self, stream: IO[bytes]) -> None:
        """Wait for a new worker's first message (it has loaded unified-planning)."""
        if self._ready:
            return
        try:
            _receive(stream, time.monotonic() + STARTUP_TIMEOUT)
        except (TimeoutError, OSError, EOFError, pickle.UnpicklingError) as e:
            reason = self._worker_log() or str(e) or type(e).__name__
            self._reap()
            raise PlanningError(f"the planner worker did not start: {reason}") from e
        self._ready = True

    def _call(self, message: tuple[Any, ...], timeout: float) -> Any:
        """Send a message and wait for the answer; kill the worker when it takes too long.

        Raises:
            TimeoutError: no answer in time (the worker was killed).
            PlanningError: the worker died or could not be started.
        """
        process = self._process
        if process is None or process.stdin is None or process.stdout is None:
            raise PlanningError("the planner worker is not running")
        try:
            self._wait_ready(process.stdout)
            _send(process.stdin, message)
            return _receive(process.stdout, time.monotonic() + timeout)
        except TimeoutError:
            self._reap()
            raise
        except (OSError, EOFError, pickle.UnpicklingError) as e:
            reason = self._worker_log() or str(e) or "it exited"
            self._reap()
            raise PlanningError(f"the planner worker failed: {reason}") from e

    # --- planning -------------------------------------------------------------------------

    def solve(self, task: PlanningTask, timeout: float | None = None) -> PlanResult:
        """Plan for a task; never raises for what an engine does (see the result's status)."""
        timeout = self.timeout if timeout is None else timeout
        with self._lock:
            began = time.monotonic()
            try:
                self._spawn()
                if self._process is not None and self._process.stdout is not None:
                    self._wait_ready(self._process.stdout)
                began = time.monotonic()  # a worker's start-up is not planning time
                result: PlanResult = self._call(
                    ("solve", self.engine, task, timeout), hard_timeout(timeout)
                )
            except TimeoutError:
                result = PlanResult(
                    PlanStatus.TIMEOUT,
                    None,
                    self.engine,
                    (f"killed after {hard_timeout(timeout):g} s (the engine ignored its timeout)",),
                )
            except PlanningError as e:
                result = PlanResult(PlanStatus.ERROR, None, self.engine, (str(e),))
        return replace(result, time=time.monotonic() - began)


class _suppress_lookup:
    """Ignore a process (group) that is already gone."""

    def __enter__(self) -> None:
        return None

    def __exit__(self, kind: type[BaseException] | None, *rest: object) -> bool:
        return kind is not None and issubclass(kind, (ProcessLookupError, PermissionError))


# --- temporary folders ------------------------------------------------------------------


def _sweep(folder: Path) -> None:
    """Remove the temporary folders of workers that are gone without cleaning up: a
    worker removes its own when its input closes, but not when it is killed together
    with dura (a power cut, a killed container)."""
    for stale in folder.glob(f"{TMP_PREFIX}*"):
        try:
            pid = int((stale / WORKER_PID).read_text())
        except (OSError, ValueError):  # no pid (yet): left over only once it is old
            with contextlib.suppress(OSError):
                if time.time() - stale.stat().st_mtime > ABANDONED:
                    shutil.rmtree(stale, ignore_errors=True)
            continue
        if not psutil.pid_exists(pid):
            shutil.rmtree(stale, ignore_errors=True)


# --- framing --------------------------------------------------------------------------


def _send(stream: IO[bytes], message: object) -> None:
    data = pickle.dumps(message, protocol=pickle.HIGHEST_PROTOCOL)
    stream.write(_HEADER.pack(len(data)) + data)
    stream.flush()


def _read_exactly(stream: IO[bytes], size: int, deadline: float | None) -> bytes:
    chunks: list[bytes] = []
    fd = stream.fileno()
    while size > 0:
        if deadline is not None:
            left = deadline - time.monotonic()
            if left <= 0 or not select.select([fd], [], [], left)[0]:
                raise TimeoutError
        chunk = os.read(fd, min(size, 1 << 20))
        if not chunk:
            raise EOFError("the planner worker exited")
        chunks.append(chunk)
        size -= len(chunk)
    return b"".join(chunks)


def _receive(stream: IO[bytes], deadline: float | None) -> Any:
    (size,) = _HEADER.unpack(_read_exactly(stream, _HEADER.size, deadline))
    return pickle.loads(_read_exactly(stream, size, deadline))  # noqa: S301 (our own worker)


# --- the worker process ------------------------------------------------------------------


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


@dataclass
class _Worker:
    """The worker's state: UP's environment, engines and parsed domains, kept warm."""

    output: Path
    engines: dict[str, Any] = field(default_factory=dict)
    domains: dict[Path, tuple[float, Any]] = field(default_factory=dict)
    env: Any = None

    def setup(self) -> None:
        import warnings

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
                raise PlanningError(f"engine '{name}' is not installed")
            self.engines[name] = OneshotPlanner(name=name)
        return self.engines[name]

    def prepare(self, engine: str, domain: Path) -> bool:
        self.domain(domain)
        self.engine(engine)
        return True

    @_capturing_output
    def solve(self, engine_name: str, task: PlanningTask, timeout: float) -> PlanResult:
        from executive.planning.problem import build

        def result(status: PlanStatus, *lines: str, **more: Any) -> PlanResult:
            return PlanResult(status, more.get("plan"), engine_name, tuple(lines), 0.0,
                              more.get("validator", ""))  # fmt: skip

        try:
            problem = build(self.domain(task.domain), task.world, task.goals, task.blocked)
            engine = self.engine(engine_name)
        except DuraError as e:
            return result(PlanStatus.ERROR, str(e))
        missing = _missing_features(engine, problem)
        if missing:
            return result(PlanStatus.UNSUPPORTED, f"unsupported features: {missing}")
        try:
            answer = engine.solve(problem, timeout=timeout)
        except Exception as e:  # an engine's own failure is a result, not a crash
            return result(PlanStatus.ERROR, f"{type(e).__name__}: {e}")
        lines = [str(m.message).splitlines()[0] for m in answer.log_messages or () if m.message]
        status = _status(answer.status.name)
        if answer.plan is None or status is not PlanStatus.SOLVED:
            return result(PlanStatus.ERROR if status is PlanStatus.SOLVED else status, *lines)
        valid, validator, reason = _validate(problem, answer.plan)
        if not valid:
            return result(PlanStatus.INVALID_PLAN, *lines, reason, validator=validator)
        from executive.planning.stn import partial_order

        try:
            plan = partial_order(problem, answer.plan)
        except DuraError as e:
            return result(PlanStatus.ERROR, *lines, str(e))
        return result(PlanStatus.SOLVED, *lines, plan=plan, validator=validator)


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


def _validate(problem: Any, plan: Any) -> tuple[bool, str, str]:
    """Check a plan with the first UP validator that supports the problem (UP's own
    before Kairos', so that a Kairos plan gets an independent check).

    Returns (valid, validator name, reason if invalid).
    """
    from unified_planning.engines import ValidationResultStatus
    from unified_planning.shortcuts import PlanValidator

    names = _VALIDATORS.get(type(plan).__name__, ())
    if not names:
        return False, "", f"no validator for a {type(plan).__name__}"
    chosen = next((n for n in names if PlanValidator(name=n).supports(problem.kind)), names[0])
    with PlanValidator(name=chosen) as validator:
        answer = validator.validate(problem, plan)
    if answer.status == ValidationResultStatus.VALID:
        return True, chosen, ""
    messages = [str(m.message).splitlines()[0] for m in answer.log_messages or ()]
    reason = answer.reason.name.lower() if answer.reason is not None else "unknown"
    return False, chosen, f"{chosen}: {reason} {'; '.join(messages)}".strip()


def _frames(stream: IO[bytes]) -> Iterator[Any]:
    while True:
        try:
            yield _receive(stream, None)
        except EOFError:
            return


def serve() -> None:
    """The worker's main loop: answer messages on stdin until it closes."""
    protocol_in = os.fdopen(os.dup(0), "rb")
    protocol_out = os.fdopen(os.dup(1), "wb")
    devnull = os.open(os.devnull, os.O_RDWR)
    os.dup2(devnull, 0)
    os.dup2(2, 1)  # stray prints go to the worker log, never into the protocol
    worker = _Worker(Path(tempfile.gettempdir()) / "engine-output.txt")
    worker.setup()
    _send(protocol_out, "ready")
    with contextlib.suppress(BrokenPipeError):  # dura died while the worker planned
        for message in _frames(protocol_in):
            kind, engine, *args = message
            try:
                answer = getattr(worker, kind)(engine, *args)
            except DuraError as e:
                answer = PlanResult(PlanStatus.ERROR, None, engine, (str(e),))
            _send(protocol_out, answer)
    # the input closed: dura is done with this worker, or died without cleaning up
    # (SIGKILL); either way the engines' temporary files go with it
    own = Path(tempfile.gettempdir())
    if own.name.startswith(TMP_PREFIX):
        shutil.rmtree(own, ignore_errors=True)


if __name__ == "__main__":
    from executive.planning.planner import (
        serve as _serve,  # so pickled classes are executive.planning.planner's
    )

    _serve()
