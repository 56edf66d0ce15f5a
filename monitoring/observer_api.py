"""The observer manager's bus API: observers listed, added, changed, removed, activated
and deactivated at run time, and the latest observations (the verbs of
:mod:`executive.bus.api.monitoring`)."""

from __future__ import annotations

from collections.abc import Mapping
from typing import TYPE_CHECKING, Any

from executive.bus.api import monitoring as api
from executive.bus.session import Bus
from executive.bus.verb import Verb
from knowledge.errors import ConfigError

if TYPE_CHECKING:
    from monitoring.observer_manager import ObserverManager


def _entry(config: Any, verb: Verb[Any, Any]) -> Mapping[str, Any]:
    if not isinstance(config, dict):
        raise ConfigError(f"{verb.key}: 'config' must be an observer entry (a mapping)")
    return config


def serve_observers(manager: ObserverManager, bus: Bus) -> list[Any]:
    """Serve the observer verbs for ``manager``; returns the queryables."""

    def add(request: api.ObserverAdd) -> api.ObserverActive:
        config = _entry(request.config, api.OBSERVER_ADD)
        observer_id = manager.add(
            config, component=request.component, name=request.name, source=api.OBSERVER_ADD.key
        )
        return api.ObserverActive(observer_id, manager.active(observer_id))

    def change(request: api.ObserverChange) -> api.ObserverActive:
        config = _entry(request.config, api.OBSERVER_CHANGE)
        manager.change(request.id, config, source=api.OBSERVER_CHANGE.key)
        return api.ObserverActive(request.id, manager.active(request.id))

    def remove(request: api.ObserverId) -> api.ObserverId:
        manager.remove(request.id)
        return request

    def deactivate(request: api.ObserverId) -> api.ObserverActive:
        manager.deactivate_observer(request.id)
        return api.ObserverActive(request.id, False)

    return [
        api.OBSERVER_LIST.serve(bus, lambda _: api.ObserversReply(manager.observers())),
        api.OBSERVER_ADD.serve(bus, add),
        api.OBSERVER_CHANGE.serve(bus, change),
        api.OBSERVER_REMOVE.serve(bus, remove),
        api.OBSERVER_ACTIVATE.serve(
            bus, lambda r: api.ObserverActive(r.id, manager.activate_observer(r.id))
        ),
        api.OBSERVER_DEACTIVATE.serve(bus, deactivate),
        api.OBSERVER_LATEST.serve(bus, lambda _: api.LatestReply(manager.latest())),
    ]
