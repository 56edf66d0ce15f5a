"""The planner's worker process: unified-planning and its engines, kept warm.

:class:`~executive.planning.planner.Planner` starts it as ``python -m
executive.planning.planner_worker`` in its own process group and temporary folder and
sends it one job at a time over stdin/stdout (pickled frames, see
:func:`~executive.planning.planner.send_frame`); each job is a method of
:class:`~executive.planning.planner_jobs.PlannerJobs`, whose answer (or
:class:`~knowledge.errors.DuraError`) goes back.
"""

from __future__ import annotations

import contextlib
import os
import shutil
import tempfile
from collections.abc import Iterator
from pathlib import Path
from typing import IO, TYPE_CHECKING, Any

from executive import fast_start
from executive.planning.planner import (
    TMP_PREFIX,
    PlanResult,
    PlanStatus,
    Progress,
    receive_frame,
    send_frame,
)
from knowledge.errors import DuraError

if TYPE_CHECKING:
    from executive.planning.planner_jobs import PlannerJobs


def warm_up(output: Path) -> PlannerJobs:
    """unified-planning and its engines loaded, ``ConfigSpace`` left until something
    uses it (:func:`executive.fast_start.import_unified_planning`); ``output``: the file
    the engines' own output goes to during a job."""
    fast_start.import_unified_planning()
    # here, not at the top: the jobs' module imports unified-planning, which must come
    # after the line above
    from executive.planning.planner_jobs import PlannerJobs

    return PlannerJobs(output)


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
        jobs = warm_up(Path(tempfile.gettempdir()) / "engine-output.txt")
        jobs.progress = lambda phase: send_frame(protocol_out, Progress(phase))
        with contextlib.suppress(BrokenPipeError):  # dura died while the worker worked
            send_frame(protocol_out, "ready")
            for message in _frames(protocol_in):
                kind, engine, *args = message
                try:
                    answer = getattr(jobs, kind)(engine, *args)
                except DuraError as e:  # a planning job's failure is a result; others raise
                    answer = (
                        PlanResult(PlanStatus.ERROR, None, engine, (str(e),))
                        if kind == "solve"
                        else e
                    )
                except Exception as e:  # unified-planning's own failure: a result, the
                    # worker stays (else the next job waits for a new one to start)
                    if kind != "solve":
                        raise
                    reason = f"{type(e).__name__}: {e}".splitlines()[0]
                    answer = PlanResult(PlanStatus.ERROR, None, engine, (reason,))
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
