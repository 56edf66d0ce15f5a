"""The one adapter to unified-planning's engines: every engine in a worker process.

:class:`Planner` is the client side. It keeps a warm worker process
(:mod:`executive.planning.planner_worker`, run as ``python -m
executive.planning.planner_worker``) that has unified-planning and the engine loaded,
and sends it one job at a time; this module also owns what both sides share: the
planning task and result types and the framing of messages. The worker runs in its own
process group, under a hard timeout: when a job runs past the engine's timeout plus a
grace period (TAMER ignores timeouts), the whole group is killed (the Aries and Fast
Downward binaries with it) and a new worker is started for the next job. The worker's
temp dir is private (Aries leaves files behind) and removed with it.

Engines: ``auto`` (the default: the first installed engine that supports the problem,
:mod:`executive.planning.engine_choice`), ``kairos`` (up-kairos), ``aries``,
``fast-downward`` (classical domains), ``tamer`` (the optional ``tamer`` extra), and
plugins: a UP engine class registered under the entry-point group ``dura.planners``
(``name = "pkg.mod:Engine"``). ``portfolio`` runs several at once
(:mod:`executive.planning.portfolio`).
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
from dataclasses import dataclass, replace
from importlib import metadata
from pathlib import Path
from typing import IO, TYPE_CHECKING, Any

import psutil

from executive.planning.goals import GoalSpec
from executive.planning.metric import Metric
from executive.planning.partial_order import PartialOrderPlan
from executive.planning.problem import World
from knowledge.description import AUTO, DEFAULT_ENGINE, PORTFOLIO
from knowledge.errors import DuraError, PlanningError

if TYPE_CHECKING:
    from knowledge.domain import DomainInfo

log = logging.getLogger("dura.planner")

BUILTIN_ENGINES = ("kairos", "aries", "fast-downward", "tamer")  # auto tries them in this order
PLUGIN_GROUP = "dura.planners"
TMP_PREFIX = "dura-planner-"  # the worker's temporary folder (engines write there)
WORKER_PID = "worker.pid"  # in that folder: whose it is
WORKER_MODULE = "executive.planning.planner_worker"  # run as python -m
ABANDONED = 3600.0  # seconds after which a folder without a worker pid is left over
STARTUP_TIMEOUT = 120.0  # seconds for a worker to import unified-planning and the engines
BUILDING = 60.0  # seconds at least to build a problem, or to validate and convert a plan
SEARCHING, SEARCHED = "searching", "searched"  # the phases of a solve job
_HEADER = struct.Struct("!Q")


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
class Progress:
    """A frame the worker sends before its answer: the job is now in ``phase``."""

    phase: str


@dataclass(frozen=True)
class PlanningTask:
    """What to plan: a domain file, a world to start from and the goals to reach,
    without the ``blocked`` actions (the robot cannot do them now), optimising ``metric``."""

    domain: Path
    world: World
    goals: tuple[GoalSpec, ...]
    blocked: frozenset[str] = frozenset()
    metric: Metric | None = None


@dataclass(frozen=True)
class PlanResult:
    """The outcome of one planning call; ``plan`` is set when ``status`` is SOLVED."""

    status: PlanStatus
    plan: PartialOrderPlan | None
    engine: str
    log: tuple[str, ...] = ()
    time: float = 0.0  # seconds, from sending the job to receiving the answer
    validator: str = ""  # the UP validator that accepted the plan
    missing: tuple[str, ...] = ()  # without a plan: goal atoms no action can make true
    notes: tuple[str, ...] = ()  # what the user should know about a plan (not optimised)

    @property
    def ok(self) -> bool:
        return self.status is PlanStatus.SOLVED

    @property
    def reason(self) -> str:
        """One line on why there is no plan (empty when solved)."""
        if self.ok:
            return ""
        last = next((line for line in reversed(self.log) if line.strip()), "")
        if last and self.status is PlanStatus.UNSUPPORTED:
            return last  # the refusal names the engine, what it lacks and who has it
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
    """Every engine dura knows (built in, then plugins), in the order ``auto`` tries them."""
    return [*BUILTIN_ENGINES, *sorted(set(plugins()) - set(BUILTIN_ENGINES))]


def choices() -> list[str]:
    """Every engine name a robot description or the CLI may choose."""
    return [AUTO, PORTFOLIO, *engine_names()]


def hard_timeout(timeout: float) -> float:
    """When a search is killed: the engine's timeout plus a grace period (the problem's
    building before it and the plan's validation after it have allowances of their own)."""
    return timeout + max(2.0, timeout / 4)


class Planner:
    """One engine in a warm worker process; :meth:`solve` is safe to call from any thread.

    Args:
        engine: an engine name (see :func:`engine_names`), or ``auto``.
        timeout: seconds the engine may search; the job is killed a little later.
        metric: what plans optimise, unless a task says (a robot description's).
    """

    def __init__(
        self, engine: str = DEFAULT_ENGINE, timeout: float = 30.0, metric: Metric | None = None
    ) -> None:
        if engine not in [AUTO, *engine_names()]:
            raise PlanningError(
                f"unknown planner engine '{engine}' (choose from {', '.join(choices())})"
            )
        if timeout <= 0:
            raise PlanningError(f"the planner timeout must be positive, not {timeout:g}")
        self.engine = engine
        self.timeout = timeout
        self.metric = metric
        self._lock = threading.Lock()
        self._process: subprocess.Popen[bytes] | None = None
        self._tmp: Path | None = None
        self._ready = False
        self.phase = ""  # where the job under way is: "", SEARCHING or SEARCHED

    def __enter__(self) -> Planner:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    # --- the worker ---------------------------------------------------------------------

    def start(self, domain: Path | None = None) -> None:
        """Start the worker now (and wait until it parsed ``domain``), so the first job
        is fast; without a domain it returns at once while the worker loads."""
        with self._lock:
            self._spawn()
            if domain is not None:
                self._call(("prepare", self.engine, Path(domain)), STARTUP_TIMEOUT)

    def describe(self, domain: Path) -> DomainInfo:
        """Parse a domain in the worker (and load the engine there): its signatures.

        Raises:
            DomainError: the domain is not valid PDDL (``file:line``).
            PlanningError: the worker failed, or the engine is not installed.
        """
        info: DomainInfo = self._job(("describe", self.engine, Path(domain)))
        return info

    def installed(self) -> list[str]:
        """The engines installed with the worker, in dura's order."""
        names: list[str] = self._job(("installed", self.engine))
        return names

    def read_world(self, domain: Path, problem: Path) -> World:
        """The objects and facts of a problem file, read in the worker.

        Raises:
            DomainError: the problem cannot be read or does not fit the domain.
            PlanningError: the worker failed.
        """
        world: World = self._job(("world", self.engine, Path(domain), Path(problem)))
        return world

    def _job(self, message: tuple[Any, ...]) -> Any:
        """Send a job that is not planning; its answer, or the error it raised."""
        with self._lock:
            try:
                self._spawn()
                answer = self._call(message, STARTUP_TIMEOUT)
            except TimeoutError as e:
                raise PlanningError(
                    f"the planner worker did not answer within {STARTUP_TIMEOUT:g} s"
                ) from e
        if isinstance(answer, DuraError):
            raise answer
        return answer

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
                [sys.executable, "-m", WORKER_MODULE],
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

    def interrupt(self) -> None:
        """Kill the worker's process group now, from any thread, also while a job waits
        for it (that job fails; the next one starts a new worker)."""
        process = self._process
        if process is not None:
            with _suppress_lookup():
                os.killpg(process.pid, signal.SIGKILL)

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
            receive_frame(stream, time.monotonic() + STARTUP_TIMEOUT)
        except (TimeoutError, OSError, EOFError, pickle.UnpicklingError) as e:
            reason = self._worker_log() or str(e) or type(e).__name__
            self._reap()
            raise PlanningError(f"the planner worker did not start: {reason}") from e
        self._ready = True

    def _call(
        self,
        message: tuple[Any, ...],
        timeout: float,
        phases: dict[str, float] | None = None,
    ) -> Any:
        """Send a message and wait for the answer; kill the worker when it takes too long.
        A :class:`Progress` frame of the worker starts a new allowance, ``phases[phase]``
        seconds (the search gets the engine's timeout, whatever building the problem took).

        Raises:
            TimeoutError: no answer in time (the worker was killed).
            PlanningError: the worker died or could not be started.
        """
        process = self._process
        if process is None or process.stdin is None or process.stdout is None:
            raise PlanningError("the planner worker is not running")
        self.phase = ""
        try:
            self._wait_ready(process.stdout)
            send_frame(process.stdin, message)
            deadline = time.monotonic() + timeout
            while True:
                answer = receive_frame(process.stdout, deadline)
                if not isinstance(answer, Progress):
                    return answer
                self.phase = answer.phase
                deadline = time.monotonic() + (phases or {}).get(answer.phase, timeout)
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
        if task.metric is None and self.metric is not None:
            task = replace(task, metric=self.metric)
        with self._lock:
            began = time.monotonic()
            try:
                self._spawn()
                if self._process is not None and self._process.stdout is not None:
                    self._wait_ready(self._process.stdout)
                began = time.monotonic()  # a worker's start-up is not planning time
                phases = {SEARCHING: hard_timeout(timeout), SEARCHED: max(BUILDING, timeout)}
                result: PlanResult = self._call(
                    ("solve", self.engine, task, timeout), max(BUILDING, timeout), phases
                )
            except TimeoutError:
                why = {
                    "": f"building the problem took more than {max(BUILDING, timeout):g} s",
                    SEARCHING: f"the engine ignored its timeout: killed after "
                    f"{hard_timeout(timeout):g} s of search",
                    SEARCHED: f"validating the plan took more than {max(BUILDING, timeout):g} s",
                }[self.phase]
                result = PlanResult(PlanStatus.TIMEOUT, None, self.engine, (why,))
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


# --- framing (both sides) ----------------------------------------------------------------


def send_frame(stream: IO[bytes], message: object) -> None:
    """Write one message: its length, then its pickle."""
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


def receive_frame(stream: IO[bytes], deadline: float | None) -> Any:
    """Read one message (``TimeoutError`` past ``deadline``, ``EOFError`` at the end)."""
    (size,) = _HEADER.unpack(_read_exactly(stream, _HEADER.size, deadline))
    return pickle.loads(_read_exactly(stream, size, deadline))  # noqa: S301 (our own worker)
