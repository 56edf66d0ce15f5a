"""The diagnosis service's decisions on a clock that someone else drives: when to
diagnose, and which results to publish (the offline replay's diagnosis).

As :class:`monitoring.diagnosis.diagnosis_service.DiagnosisService` does on its thread: it
learns observers from their observations and keeps the model's nodes as it is told;
it diagnoses ``settle`` seconds after a verdict or the model changed (what changes
meanwhile is diagnosed with it), publishes a result that differs from the last one
published, and, while that one is faulty, wakes every ``period`` seconds and
publishes it again. A change while it waits to repeat starts a settle instead.
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
    """A result the service publishes at ``time``; ``changed``: not a repetition."""

    result: DiagnosisResult
    time: float
    changed: bool


class TimedDiagnosis:
    """The diagnosis service without its thread; the caller calls :meth:`wake` at
    :attr:`wake_at`.

    Args:
        engine: the diagnosis engine (its model starts empty, as live).
        settle, period: the service's timing.
    """

    def __init__(
        self, engine: DiagnosisEngine, *, settle: float = SETTLE, period: float = PERIOD
    ) -> None:
        self.engine = engine
        self.settle = settle
        self.period = period
        self.wake_at: float | None = None  # when the service's loop runs next
        self.last = DiagnosisResult(Status.OK)  # the last result published
        self._settling = False
        self._published = 0.0
        self._ignored: set[str] = set()

    def observe(self, info: ObservationInfo, t: float) -> None:
        """Take in an observation; an observer the model lacks is learnt, as live."""
        try:
            changed = self.engine.observe(info)
        except ConfigError as e:
            changed = learning.learn(self.engine, info) and self.engine.observe(info)
            if not changed and str(e) not in self._ignored:
                self._ignored.add(str(e))  # say once why observations of a kind are ignored
                log.info("ignored: %s", e)
        if changed:
            self._changed(t)

    def change_model(self, action: UpdateAction, nodes: list[Node], t: float) -> None:
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
        self._changed(t)

    def wake(self, t: float) -> Published | None:
        """Run one turn of the service's loop at ``t``; return what it publishes, if any."""
        dirty, self._settling = self._settling, False
        self.wake_at = None
        try:
            result = self.engine.diagnose() if dirty else self.last
        except DuraError:
            log.exception("diagnosis failed")
            result = self.last
        published = None
        changed = self._differs(result)
        if changed or (result.status is not Status.OK and t - self._published >= self.period):
            self.last, self._published = result, t
            published = Published(result, t, changed)
        if self.last.status is not Status.OK:
            self.wake_at = t + self.period
        return published

    def _changed(self, t: float) -> None:
        if not self._settling:  # a change while settling is diagnosed with the others
            self._settling = True
            self.wake_at = t + self.settle

    def _differs(self, result: DiagnosisResult) -> bool:
        last = self.last
        return (result.status, result.diagnoses, result.conflicts) != (
            last.status,
            last.diagnoses,
            last.conflicts,
        )
