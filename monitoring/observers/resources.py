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

from executive.bus.keys import RESOURCES
from executive.bus.payloads import NOT_AVAILABLE, NodeInfo
from executive.bus.session import Message
from knowledge.errors import BusError
from monitoring.config_entry import Entry
from monitoring.filter import FilterConfig, FilterState, read_filter
from monitoring.observer import Environment, Handler, Observer, ObserverConfig, ObserverResult
from monitoring.state import ObserverState, Verdict, classify, read_states

NO_FILTER = FilterConfig("nofilter")


@dataclass(frozen=True)
class WatchedNode:
    name: str
    cpu_filter: FilterConfig
    mem_filter: FilterConfig
    states: tuple[ObserverState, ...]


@dataclass(frozen=True, kw_only=True)
class ResourcesConfig(ObserverConfig):
    nodes: tuple[WatchedNode, ...]


def node_name(entry: Entry) -> str | None:
    name = entry.text("name", required=True)
    return name.strip("/") if name is not None and name.strip("/") else None


def read_node(entry: Entry, owner: str) -> WatchedNode | None:
    name = node_name(entry)
    if name is not None:
        entry.what = f"node '{name}' of the {owner}"
    filters = []
    for key, label in (("cpu_filter", "CPU"), ("mem_filter", "memory")):
        sub = entry.entry(key, f"the {label} filter of {entry.what}")
        filters.append(read_filter(sub) if sub is not None else NO_FILTER)
    states = read_states(entry, ("cpu", "memory"))
    entry.close()
    cpu, memory = filters
    if name is None or cpu is None or memory is None or not states:
        return None
    return WatchedNode(name, cpu, memory, states)


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
    config: ResourcesConfig

    def __init__(self, config: ResourcesConfig, environment: Environment | None = None) -> None:
        super().__init__(config, environment)
        self._queue: deque[Message] = deque()
        self._filters = [(n.cpu_filter.make(), n.mem_filter.make()) for n in config.nodes]
        self._latest: dict[str, NodeInfo] | None = None

    @classmethod
    def read(cls, entry: Entry, common: ObserverConfig) -> ResourcesConfig | None:
        entry.text("resource_topic")
        what = f"node {{n}} of the {entry.what}"
        nodes = [read_node(e, entry.what) for e in entry.entries("nodes", what, required=True)]
        return ResourcesConfig(**common.common(), nodes=tuple(n for n in nodes if n is not None))

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
