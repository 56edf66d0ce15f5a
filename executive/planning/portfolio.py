"""Several engines at once: a :class:`Portfolio` of :class:`~executive.planning.planner.Planner`
clients, each with its own worker process under its own hard timeout.

It answers like one planner. A job that is not planning (describe, read a world) goes
to its first engine. A plan is the first valid one any engine finds (the others are
stopped: their workers are killed, and start again for the next job), or, when the task
optimises the makespan, the shortest one found by the timeout.
"""

from __future__ import annotations

import queue
import threading
import time
from collections.abc import Sequence
from dataclasses import replace
from pathlib import Path
from typing import TYPE_CHECKING

from executive.planning.metric import Metric, read_metric
from executive.planning.planner import Planner, PlanningTask, PlanResult, PlanStatus, engine_names
from knowledge.description import AUTO, PORTFOLIO
from knowledge.errors import DuraError, PlanningError

if TYPE_CHECKING:
    from knowledge.description import PlannerSpec

# The order in which results that are not plans explain the failure best.
_WORST_FIRST = (
    PlanStatus.ERROR,
    PlanStatus.UNSUPPORTED,
    PlanStatus.TIMEOUT,
    PlanStatus.NOT_FOUND,
    PlanStatus.INVALID_PLAN,
    PlanStatus.UNSOLVABLE,
)


class Portfolio(Planner):
    """Engines in parallel, with the :class:`Planner` interface; it is its first engine's
    planner itself (which also answers the jobs that are not planning).

    Args:
        engines: engine names; none: every installed engine (asked of the first worker).
        timeout: seconds each engine may search.
    """

    def __init__(
        self, engines: Sequence[str] = (), timeout: float = 30.0, metric: Metric | None = None
    ) -> None:
        for name in engines:
            if name not in engine_names():
                raise PlanningError(
                    f"a portfolio runs engines, not '{name}' (choose from "
                    f"{', '.join(engine_names())})"
                )
        super().__init__(engines[0] if engines else AUTO, timeout, metric)
        self._wanted = tuple(engines)
        self._others: list[Planner] | None = None

    def members(self) -> list[Planner]:
        """The member planners, this one first (made on first use: without engines named,
        the worker says which are installed)."""
        if self._others is None:
            names = list(self._wanted) or self.installed()
            if not names:
                raise PlanningError("no planning engine is installed")
            self.engine = names[0]
            self._others = [Planner(n, self.timeout, self.metric) for n in names[1:]]
        return [self, *self._others]

    @property
    def engines(self) -> list[str]:
        return [m.engine for m in self.members()]

    def start(self, domain: Path | None = None) -> None:
        """Start every member's worker (and wait until each parsed ``domain``)."""
        others = self.members()[1:]
        threads = [threading.Thread(target=m.start, args=(domain,)) for m in others]
        for t in threads:
            t.start()
        super().start(domain)
        for t in threads:
            t.join()

    def interrupt(self) -> None:
        super().interrupt()
        for m in self._others or ():
            m.interrupt()

    def close(self) -> None:
        super().close()
        for m in self._others or ():
            m.close()

    def solve(self, task: PlanningTask, timeout: float | None = None) -> PlanResult:
        """The first valid plan, or the shortest by the timeout when the task optimises
        the makespan; without a plan, every engine's reason."""
        try:
            members = self.members()
        except DuraError as e:
            return PlanResult(PlanStatus.ERROR, None, PORTFOLIO, (str(e),))
        began = time.monotonic()
        metric = task.metric or self.metric
        shortest = metric is not None and metric.expression is None
        answers: queue.Queue[tuple[int, PlanResult]] = queue.Queue()

        def run(i: int) -> None:
            answers.put((i, Planner.solve(members[i], task, timeout)))

        threads = [
            threading.Thread(target=run, args=(i,), daemon=True) for i in range(len(members))
        ]
        for t in threads:
            t.start()
        results: dict[int, PlanResult] = {}
        while len(results) < len(members):
            i, result = answers.get()
            results[i] = result
            if result.ok and not shortest:
                break
        for i, m in enumerate(members):
            if i not in results:  # still searching: not needed (it restarts next time)
                Planner.interrupt(m)
        for t in threads:
            t.join()
        return replace(_pick(list(results.values())), time=time.monotonic() - began)


def _pick(results: list[PlanResult]) -> PlanResult:
    """The shortest plan; without one, a failure whose reason is every engine's."""
    solved = [r for r in results if r.ok and r.plan is not None]
    if solved:
        return min(solved, key=lambda r: r.plan.makespan if r.plan is not None else 0.0)
    telling = max(results, key=lambda r: _WORST_FIRST.index(r.status))
    reasons = "; ".join(r.reason for r in results)
    return PlanResult(telling.status, None, PORTFOLIO, (*telling.log, reasons))


def planner_for(spec: PlannerSpec) -> Planner:
    """The planner a robot description's ``planner:`` asks for: one engine, or a
    portfolio (``engine: portfolio`` or a ``portfolio:`` list)."""
    metric = read_metric(spec.metric) if spec.metric else None
    if spec.engine == PORTFOLIO or spec.portfolio:
        return Portfolio(spec.portfolio, spec.timeout, metric)
    return Planner(spec.engine, spec.timeout, metric)
