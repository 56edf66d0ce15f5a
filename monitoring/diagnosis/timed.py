"""The diagnosis service's decisions on a clock that someone else drives: when to
diagnose, and which results to publish (the offline replay's diagnosis).

As :class:`monitoring.diagnosis.diagnosis_service.DiagnosisService` does on its thread: it
learns observers from their observations and keeps the model's nodes as it is told;
it diagnoses ``settle`` seconds after a verdict or the model changed (what changes
meanwhile is diagnosed with it), publishes a result that differs from the last one
published, and, while that one is faulty, wakes every ``period`` seconds and
publishes it again. A change while it waits to repeat starts a settle instead. Its
times are integer nanoseconds, as the replay's clock: float seconds since the epoch
are some hundred nanoseconds off, enough to put a diagnosis before an observer loop
due at the same instant.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass

from executive.bus.payloads import ObservationInfo
from knowledge.errors import ConfigError, DuraError
from monitoring.diagnosis import learning
from monitoring.diagnosis.diagnosis_service import PERIOD, SETTLE
from monitoring.diagnosis.engine import DiagnosisEngine
from monitoring.diagnosis.model import ModelUpdate, Node, UpdateAction
from monitoring.diagnosis.result import DiagnosisResult, Status

log = logging.getLogger("dura.diagnosis")


@dataclass(frozen=True)
class Published:
    """A result the service publishes at ``time_ns``; ``changed``: not a repetition."""

    result: DiagnosisResult
    time_ns: int
    changed: bool


class TimedDiagnosis:
    """The diagnosis service without its thread; the caller calls :meth:`wake` at
    :attr:`wake_at_ns`.

    Args:
        engine: the diagnosis engine (its model starts empty, as live).
        settle, period: the service's timing, in seconds.
    """

    def __init__(
        self, engine: DiagnosisEngine, *, settle: float = SETTLE, period: float = PERIOD
    ) -> None:
        self.engine = engine
        self.settle_ns = round(settle * 1e9)
        self.period_ns = round(period * 1e9)
        self.wake_at_ns: int | None = None  # when the service's loop runs next
        self.last = DiagnosisResult(Status.OK)  # the last result published
        self._settling = False
        self._published_ns = 0
        self._ignored: set[str] = set()

    def observe(self, info: ObservationInfo, t_ns: int) -> None:
        """Take in an observation at ``t_ns``; an observer the model lacks is learnt, as
        live."""
        try:
            changed = self.engine.observe(info)
        except ConfigError as e:
            changed = learning.learn(self.engine, info) and self.engine.observe(info)
            if not changed and str(e) not in self._ignored:
                self._ignored.add(str(e))  # say once why observations of a kind are ignored
                log.info("ignored: %s", e)
        if changed:
            self._changed(t_ns)

    def change_model(self, action: UpdateAction, nodes: list[Node], t_ns: int) -> None:
        """Add nodes that are not in the model, or remove those that are (with the
        observers that watched only them), as the task executor asks live."""
        modelled = {n.name for n in self.engine.model.nodes}
        nodes = [n for n in nodes if (n.name in modelled) == (action is UpdateAction.REMOVE)]
        if not nodes:
            return
        update = learning.without_orphans(self.engine.model, ModelUpdate(action, tuple(nodes)))
        try:
            self.engine.update(update)
        except ConfigError as e:
            names = ", ".join(n.name for n in nodes)
            log.warning("diagnosis model refused %s %s: %s", action.value, names, e)
            return
        self._changed(t_ns)

    def wake(self, t_ns: int) -> Published | None:
        """Run one turn of the service's loop at ``t_ns``; return what it publishes, if
        any."""
        dirty, self._settling = self._settling, False
        self.wake_at_ns = None
        try:
            result = self.engine.diagnose() if dirty else self.last
        except DuraError:
            log.exception("diagnosis failed")
            result = self.last
        published = None
        changed = self._differs(result)
        repeat = t_ns - self._published_ns >= self.period_ns
        if changed or (result.status is not Status.OK and repeat):
            self.last, self._published_ns = result, t_ns
            published = Published(result, t_ns, changed)
        if self.last.status is not Status.OK:
            self.wake_at_ns = t_ns + self.period_ns
        return published

    def _changed(self, t_ns: int) -> None:
        if not self._settling:  # a change while settling is diagnosed with the others
            self._settling = True
            self.wake_at_ns = t_ns + self.settle_ns

    def _differs(self, result: DiagnosisResult) -> bool:
        last = self.last
        return (result.status, result.diagnoses, result.conflicts) != (
            last.status,
            last.diagnoses,
            last.conflicts,
        )
