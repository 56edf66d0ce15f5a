"""The component observer (alias ``activated``): are nodes running? (thesis 6.2.5)

Configuration::

    - type: component
      start_up_time: 2.0
      nodes: [lidar, robot_base]        # or the thesis form: [{name: lidar}, ...]

Each loop every node is ``GENERAL_OK`` ("running") or ``NOT_AVAILABLE`` ("not
running"). A node runs if the launcher's last state for it is alive (starting, ready,
paused, stopping); for a node the launcher never reported on (one dura does not start),
if the latest resource info lists it without an error. An observer is only active
while its own component runs, so it is useful on a component that depends on the
nodes it watches, e.g. a behavior watching the functionalities it needs. The tug key
``resource_topic`` is accepted and ignored.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Annotated, Any

from executive.bus.keys import RESOURCES
from executive.bus.message import Message
from executive.bus.payloads import GENERAL_OK, NOT_AVAILABLE, NodeInfo
from executive.bus.states import Lifecycle
from knowledge.conventions import Convert, Label
from knowledge.typed_reader import MISSING, Place, open_entry, read_value
from monitoring.filter import Text
from monitoring.observer import Environment, Handler, Observer, ObserverConfig, ObserverResult
from monitoring.observers.resources import NodeName, absence, node_infos
from monitoring.state import Verdict


def _nodes(value: Any, place: Place) -> Any:
    """Nodes by name, or as entries ``{name: ...}``; each once."""
    names: list[str] = []

    def node(item: Any, place: Place) -> Any:
        if isinstance(item, str) and item.strip("/"):
            names.append(item.strip("/"))
            return MISSING
        what = f"node {len(names) + 1} of the {place.entry.what}"
        entry = open_entry(item, place.source, place.path, what, place=place)
        if entry is not None:
            name = entry.read("name", NodeName, None, required=True)
            entry.close()
            if name is not None:
                names.append(name)
        return MISSING

    each = Annotated[tuple[Annotated[Any, Convert(node)], ...], Label("node {n}")]
    read_value(each, value, place)
    return tuple(dict.fromkeys(names))


@dataclass(frozen=True, kw_only=True)
class ComponentConfig(ObserverConfig):
    resource_topic: Text | None = None  # tug's: accepted and ignored
    nodes: Annotated[tuple[str, ...], Convert(_nodes), Label("node {n}")]


class ComponentObserver(Observer):
    type = "component"
    config_type = ComponentConfig
    config: ComponentConfig

    def __init__(self, config: ComponentConfig, environment: Environment | None = None) -> None:
        super().__init__(config, environment)
        self._infos: dict[str, NodeInfo] | None = None

    def inputs(self) -> list[tuple[str, Handler]]:
        return [(RESOURCES, self._on_resources)]

    def _on_resources(self, message: Message) -> None:
        infos = node_infos(message)
        if infos is not None:
            self._infos = infos

    def _reset(self, now: float) -> None:
        self._infos = None

    def _why_not_running(self, name: str) -> str | None:
        state = self.environment.component_state(name)
        if isinstance(state, Lifecycle):
            return None if state.is_alive else f"'{name}' is {state.value}"
        if self._infos is None:
            return f"nothing is known of '{name}' (no launcher state, no resource info)"
        return absence(name, self._infos.get(name))

    def _observe(self, now: float) -> list[ObserverResult]:
        results: list[ObserverResult] = []
        for name in self.config.nodes:
            why = self._why_not_running(name)
            if why is None:
                results.append(
                    self.result(
                        (name,), Verdict(GENERAL_OK, "running", f"'{name}' is running"), now
                    )
                )
            else:
                results.append(
                    self.result((name,), Verdict(NOT_AVAILABLE, "not running", why), now)
                )
        return results
