"""The resources observer: CPU and memory of nodes, from the resource monitor (thesis 6.2.5).

Configuration::

    - type: resources
      start_up_time: 5.0
      nodes:
        - name: lidar
          cpu_filter: {type: mean, window_size: 5}     # optional (default: nofilter)
          mem_filter: {type: median, window_size: 5}   # optional
          states:
            - state: normal
              number: 1
              cpu: {type: less_than, less_than: 80.0}        # percent of one core
              memory: {type: less_than, less_than: 2.0e8}    # resident bytes

It listens to the resource monitor's ``resources`` payload
(``{"stamp", "hostname", "nodes": [NodeInfo]}``). A node missing from the latest
resource info, or listed with an error, is ``NOT_AVAILABLE``. Without any resource
info (no resource monitor running) nothing is reported. The tug key
``resource_topic`` is accepted and ignored.
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass
from typing import Annotated, Any

from executive.bus.keys import RESOURCES
from executive.bus.message import Message
from executive.bus.payloads import NOT_AVAILABLE, NodeInfo
from knowledge.conventions import Check, Label, Titles
from knowledge.errors import BusError
from knowledge.typed_reader import MISSING, Entry, Place
from monitoring.filter import FilterConfig, FilterState, Text
from monitoring.observer import Environment, Handler, Observer, ObserverConfig, ObserverResult
from monitoring.state import ObserverState, Verdict, classify, states_checking

NO_FILTER = FilterConfig("nofilter")


def _node(name: str, place: Place) -> Any:
    return name.strip("/") or MISSING  # a name of slashes names no node


NodeName = Annotated[Text, Check(_node)]
"""The name of a node (a leading '/', ROS's, dropped)."""


@dataclass(frozen=True, kw_only=True)
class WatchedNode:
    name: Annotated[NodeName, Titles("node '{value}' of the {owner}")]
    cpu_filter: Annotated[FilterConfig, Label("the CPU filter of {what}")] = NO_FILTER
    mem_filter: Annotated[FilterConfig, Label("the memory filter of {what}")] = NO_FILTER
    states: Annotated[tuple[ObserverState, ...], states_checking("cpu", "memory")]

    def after_read(self, entry: Entry) -> WatchedNode | None:
        return self if self.states else None


@dataclass(frozen=True, kw_only=True)
class ResourcesConfig(ObserverConfig):
    resource_topic: Text | None = None  # tug's: accepted and ignored
    nodes: Annotated[tuple[WatchedNode, ...], Label("node {n} of the {what}")]


def node_infos(message: Message) -> dict[str, NodeInfo] | None:
    """The node infos of a ``resources`` message by name; ``None`` if it is malformed."""
    try:
        nodes = message.payload.get("nodes")
        if not isinstance(nodes, list):
            return None
        return {info.name: info for info in (NodeInfo.from_payload(n) for n in nodes)}
    except (BusError, KeyError, TypeError, ValueError, AttributeError):
        return None


def absence(name: str, info: NodeInfo | None) -> str | None:
    """Why a node counts as not running in a resource info, or ``None`` if it runs."""
    if info is None:
        return f"'{name}' is not in the resource info"
    if info.error:
        return f"'{name}': {info.error}"
    return None


class ResourcesObserver(Observer):
    type = "resources"
    config_type = ResourcesConfig
    config: ResourcesConfig

    def __init__(self, config: ResourcesConfig, environment: Environment | None = None) -> None:
        super().__init__(config, environment)
        self._queue: deque[Message] = deque()
        self._filters = [(n.cpu_filter.make(), n.mem_filter.make()) for n in config.nodes]
        self._latest: dict[str, NodeInfo] | None = None

    def inputs(self) -> list[tuple[str, Handler]]:
        return [(RESOURCES, self._queue.append)]

    def _reset(self, now: float) -> None:
        self._queue.clear()
        self._latest = None
        for cpu, memory in self._filters:
            cpu.reset()
            memory.reset()

    def _observe(self, now: float) -> list[ObserverResult]:
        for _ in range(len(self._queue)):
            infos = node_infos(self._queue.popleft())
            if infos is None:
                continue
            self._latest = infos
            for node, (cpu, memory) in zip(self.config.nodes, self._filters, strict=True):
                info = infos.get(node.name)
                if absence(node.name, info) is None and info is not None:
                    cpu.update(info.cpu)
                    memory.update(info.memory)
        if self._latest is None:
            return []
        results: list[ObserverResult] = []
        for node, (cpu, memory) in zip(self.config.nodes, self._filters, strict=True):
            missing = absence(node.name, self._latest.get(node.name))
            if missing is not None:
                verdict = Verdict(NOT_AVAILABLE, "not running", missing)
                results.append(self.result((node.name,), verdict, now))
                continue
            measured: dict[str, FilterState] = {}
            for quantity, values_of in (("cpu", cpu), ("memory", memory)):
                state = values_of.state()
                if state is not None:
                    measured[quantity] = state
            verdict = classify(node.states, measured)
            values = {q: s.value for q, s in measured.items()}
            results.append(self.result((node.name,), verdict, now, values=values))
        return results
