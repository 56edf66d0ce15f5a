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

from executive.bus.keys import RESOURCES
from executive.bus.payloads import GENERAL_OK, NOT_AVAILABLE, NodeInfo
from executive.bus.session import Message
from executive.bus.states import Lifecycle
from monitoring.config_entry import Entry
from monitoring.observer import Environment, Handler, Observer, ObserverConfig, ObserverResult
from monitoring.observers.resources import absence, node_infos, node_name
from monitoring.state import Verdict


@dataclass(frozen=True, kw_only=True)
class ComponentConfig(ObserverConfig):
    nodes: tuple[str, ...]


class ComponentObserver(Observer):
    type = "component"
    config: ComponentConfig

    def __init__(self, config: ComponentConfig, environment: Environment | None = None) -> None:
        super().__init__(config, environment)
        self._infos: dict[str, NodeInfo] | None = None

    @classmethod
    def read(cls, entry: Entry, common: ObserverConfig) -> ComponentConfig | None:
        entry.text("resource_topic")
        nodes: list[str] = []
        for where, item in entry.items("nodes", required=True):
            if isinstance(item, str) and item.strip("/"):
                nodes.append(item.strip("/"))
                continue
            node = Entry(item, entry.source, where, f"node {len(nodes) + 1} of the {entry.what}")
            if node.valid:
                name = node_name(node)
                node.close()
                if name is not None:
                    nodes.append(name)
        return ComponentConfig(**common.common(), nodes=tuple(dict.fromkeys(nodes)))

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
