"""The diagnosis engine as a service: observations in, diagnoses out, on the bus.

It keeps the newest observation of every observer, serves model updates on
``diagnosis/model`` (the task executor calls it as components start and stop), and
diagnoses on a thread of its own whenever an observer's verdict or the model changes.
Bursts are coalesced: the thread waits ``settle`` seconds after the first change and
then diagnoses everything that arrived meanwhile. It publishes on ``diagnoses`` when
the result changes, repeats a faulty result every ``period`` seconds (so that repair
rules can count occurrences), and publishes one all-clear (status OK) when the faults
are gone.
"""

from __future__ import annotations

import logging
import threading
import time
from typing import Any

from executive.bus.api import monitoring as api
from executive.bus.keys import DIAGNOSES, OBSERVATIONS
from executive.bus.payloads import ObservationInfo
from executive.bus.service import Context, Service
from knowledge.errors import BusError, ConfigError, DuraError
from monitoring.diagnosis import learning
from monitoring.diagnosis.engine import DiagnosisEngine
from monitoring.diagnosis.model import ModelUpdate
from monitoring.diagnosis.result import DiagnosisResult, Status

log = logging.getLogger("dura.diagnosis")

SETTLE = 0.02  # seconds to wait for the rest of a burst of changes before diagnosing
PERIOD = 1.0  # seconds between repetitions of a faulty result


class DiagnosisService(Service):
    """Continuous diagnosis over the bus.

    Args:
        context: robot, bus and knowledge base.
        exonerate: an OK topic observation clears that topic (default: the thesis model).
        max_card: list only diagnoses of at most this many components.
        timeout: seconds one diagnosis may take (then TIMEOUT with what was found).
        settle: seconds to wait for more changes before diagnosing.
        period: seconds between repetitions of a faulty result.
        learn: (the executive's mode) an observation of an observer the model lacks
            adds that observer, if
            its resources are in the model (the model's nodes come from the task
            executor, as components start and stop); a REMOVE of nodes removes the
            observers that watched only them. Off: such observations are ignored and
            such a REMOVE is refused, as the thesis' engine does.
    """

    name = "diagnosis"

    def __init__(
        self,
        context: Context,
        *,
        exonerate: bool = False,
        max_card: int | None = None,
        timeout: float = 2.0,
        settle: float = SETTLE,
        period: float = PERIOD,
        learn: bool = False,
    ) -> None:
        super().__init__(context)
        self.learn = learn
        self.engine = DiagnosisEngine(exonerate=exonerate, max_card=max_card, timeout=timeout)
        self.settle = settle
        self.period = period
        self._changed = threading.Condition()
        self._dirty = False
        self._running = False
        self._thread: threading.Thread | None = None
        self._last: DiagnosisResult = DiagnosisResult(Status.OK)
        self._ignored: set[str] = set()
        self._entities: list[Any] = []

    # --- lifecycle ----------------------------------------------------------------------

    def on_activate(self) -> None:
        bus = self.context.bus
        self._running = True
        self._thread = threading.Thread(target=self._loop, name="dura-diagnosis", daemon=True)
        self._thread.start()
        self._entities = [
            bus.subscribe(OBSERVATIONS, self._on_observation),
            api.DIAGNOSIS_MODEL_CHANGE.serve(bus, self._on_model),
            api.DIAGNOSIS_MODEL_READ.serve(bus, lambda _: self._on_model(api.ModelChange("GET"))),
            api.DIAGNOSIS_EXONERATE.serve(bus, self._on_exonerate),
        ]

    def on_deactivate(self) -> None:
        with self._changed:
            self._running = False
            self._changed.notify_all()
        for entity in self._entities:
            entity.undeclare()
        self._entities = []
        if self._thread is not None:
            self._thread.join(timeout=10)
            self._thread = None

    @property
    def last(self) -> DiagnosisResult:
        """The newest result published (OK until something failed)."""
        return self._last

    # --- input ----------------------------------------------------------------------

    def _on_observation(self, message: Any) -> None:
        try:
            info = ObservationInfo.from_payload(message.payload)
        except (KeyError, ValueError, TypeError) as e:
            raise BusError(f"malformed observation: {e}") from e
        with self._changed:
            try:
                changed = self.engine.observe(info)
            except ConfigError as e:
                if not (self.learn and self._learn(info)):
                    self._report_ignored(str(e))
                    return
                changed = self.engine.observe(info)
            if changed:
                self._dirty = True
                self._changed.notify()

    def _learn(self, info: ObservationInfo) -> bool:
        """Add the observer that made an observation to the model, if it fits (see
        :mod:`.learning`); whether it did."""
        return learning.learn(self.engine, info)

    def _without_orphans(self, update: ModelUpdate) -> ModelUpdate:
        """A REMOVE of nodes also removes the observers that watch only what they had."""
        return learning.without_orphans(self.engine.model, update) if self.learn else update

    def _report_ignored(self, reason: str) -> None:
        """Say once why observations of one kind are ignored."""
        if reason not in self._ignored:
            self._ignored.add(reason)
            log.warning("ignored: %s", reason)

    def _on_model(self, request: api.ModelChange) -> api.ModelReply:
        """Apply a model update; a refused one answers with the reason."""
        if request.action.upper() == "GET":
            with self._changed:
                return api.ModelReply(True, self.engine.model.to_payload())
        try:
            update = ModelUpdate.from_payload(request.to_payload())
            with self._changed:
                model = self.engine.update(self._without_orphans(update))
                self._dirty = True
                self._changed.notify()
        except DuraError as e:
            log.info("model update refused: %s", e)
            return api.ModelReply(False, error=str(e))
        return api.ModelReply(True, model.to_payload())

    def _on_exonerate(self, request: api.ExonerationChange) -> api.Exoneration:
        """Switch exoneration (an OK topic observation clears its topics) at run time; the
        diagnosis is computed again at once. The switch lasts until the service stops."""
        wanted = request.on
        with self._changed:
            if wanted is None or wanted == self.engine.exonerate:
                return api.Exoneration(self.engine.exonerate)
            self.engine.exonerate = wanted
            self._dirty = True
            self._changed.notify()
        log.info("exoneration %s", "on" if wanted else "off")
        self.context.kb.log_event("EXONERATION", "diagnosis", {"on": wanted})
        return api.Exoneration(wanted)

    # --- the diagnosing thread ----------------------------------------------------------

    def _loop(self) -> None:
        published = 0.0
        while True:
            with self._changed:
                wait = self.period if self._last.status is not Status.OK else None
                if not self._dirty and self._running:
                    self._changed.wait(wait)
                if not self._running:
                    return
                dirty = self._dirty
            if dirty:
                time.sleep(self.settle)  # let the rest of a burst arrive
            with self._changed:
                self._dirty = False
                try:
                    result = self.engine.diagnose() if dirty else self._last
                except DuraError:
                    log.exception("diagnosis failed")
                    continue
            now = time.time()
            if self._differs(result) or (
                result.status is not Status.OK and now - published >= self.period
            ):
                self._publish(result, now)
                published = now

    def _differs(self, result: DiagnosisResult) -> bool:
        last = self._last
        return (result.status, result.diagnoses, result.conflicts) != (
            last.status,
            last.diagnoses,
            last.conflicts,
        )

    def _publish(self, result: DiagnosisResult, stamp: float) -> None:
        self._last = result
        try:
            self.context.bus.publish(DIAGNOSES, result.to_info(stamp).to_payload())
        except DuraError:
            log.exception("cannot publish the diagnosis")
