"""How the diagnosis model learns its observers from their observations (the executive's
mode), shared by the diagnosis service and the offline replay.

The model's nodes follow the components that run; its observers describe themselves by
their observations: an observation of an observer the model lacks adds that observer
if its resources are in the model, and a REMOVE of nodes also removes the observers
that watched only what those nodes had.
"""

from __future__ import annotations

import logging

from executive.bus.payloads import ObservationInfo
from knowledge.errors import ConfigError
from monitoring.diagnosis.engine import DiagnosisEngine
from monitoring.diagnosis.model import ModelObserver, ModelUpdate, SystemDescription, UpdateAction

log = logging.getLogger("dura.diagnosis")


def learn(engine: DiagnosisEngine, info: ObservationInfo) -> bool:
    """Add the observer that made an observation to the engine's model if it fits the
    model's nodes; whether it did."""
    try:
        observer = ModelObserver.make(info.type, info.resource, info.callerids)
    except ConfigError:
        return False
    if engine.model.problem(observer) is not None:
        return False
    engine.update(ModelUpdate(UpdateAction.ADD, observers=(observer,)))
    log.info("learned observer %s from its observation", observer)
    return True


def without_orphans(model: SystemDescription, update: ModelUpdate) -> ModelUpdate:
    """Extend a REMOVE of nodes to the observers that watch only what they had."""
    if update.action is not UpdateAction.REMOVE or not update.nodes:
        return update
    gone = {n.name for n in update.nodes}
    rest = SystemDescription(tuple(n for n in model.nodes if n.name not in gone), ())
    orphans = tuple(o for o in model.observers if o not in update.observers and rest.problem(o))
    return ModelUpdate(update.action, update.nodes, update.observers + orphans)
