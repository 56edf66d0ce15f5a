"""The resource monitor (thesis 6.2.4): CPU and memory of each component's process tree.

It learns the components' processes from the launcher's reports on
``component/*/state`` and publishes a :class:`~executive.bus.payloads.ResourceInfo` on
``resources`` at its rate (default 1 Hz). A host agent measures the processes it starts
itself and publishes on ``host/<name>/resources``, the only resource key its login may
use; the monitor passes on from there the components placed on that host, and only
those: a host speaks only for its own processes. A component whose process vanished (or is a
zombie) while it should be alive is reported with an ``error``. CPU is measured between
two samples, so a process's first report shows 0 %.
"""

from __future__ import annotations

import contextlib
import logging
import socket
import threading
import time
from collections.abc import Collection
from typing import Any

import psutil

from executive.bus.keys import RESOURCES, component, host
from executive.bus.message import Message
from executive.bus.payloads import ComponentState, NodeInfo, ResourceInfo
from executive.bus.service import Context, Service
from executive.bus.session import Bus
from knowledge.errors import ConfigError, DuraError

log = logging.getLogger("dura.resources")

HOST_RESOURCES = "resources"  # a host agent's leaf: host/<name>/resources


class ResourceMonitor(Service):
    """Publishes the resource use of every running component (of this computer's, when
    ``components`` names them: the others run on host agents, which measure their own).

    Args:
        rate: samples per second.
        components: the components to measure (default: all).
        hostname: the name in each report (default: this computer's).
    """

    name = "resource-monitor"

    def __init__(
        self,
        context: Context,
        *,
        rate: float = 1.0,
        components: Collection[str] | None = None,
        hostname: str | None = None,
    ) -> None:
        super().__init__(context)
        self.sampler = ResourceSampler(context.bus, rate=rate, hostname=hostname)
        self.components = None if components is None else frozenset(components)
        self._subscribers: list[Any] = []

    @property
    def hostname(self) -> str:
        return self.sampler.hostname

    def on_activate(self) -> None:
        bus = self.context.bus
        self._subscribers = [
            bus.subscribe(component("*", "state"), self._on_state),
            bus.subscribe(host("*", HOST_RESOURCES), self._on_host),
        ]
        self.sampler.start()

    def on_deactivate(self) -> None:
        self.sampler.stop()
        for subscriber in self._subscribers:
            with contextlib.suppress(Exception):
                subscriber.undeclare()
        self._subscribers = []

    def _on_host(self, message: Message) -> None:
        """Pass a host agent's report on, with only the components placed on that host."""
        name = message.key.split("/")[1]
        try:
            info = ResourceInfo.from_payload(message.payload)
        except (KeyError, ValueError, TypeError) as e:
            log.warning("malformed resources of host '%s': %s", name, e)
            return
        own = set(self.context.robot.placed_on(name))
        nodes = tuple(n for n in info.nodes if n.name in own)
        if len(nodes) < len(info.nodes):
            others = sorted({n.name for n in info.nodes} - own)[:5]
            log.warning("host '%s' reported resources of %s, not its own: ignored", name, others)
        self.context.bus.publish(RESOURCES, ResourceInfo(name, nodes, info.stamp).to_payload())

    def measure(self) -> ResourceInfo:
        """One sample of every tracked component."""
        return self.sampler.measure()

    def _on_state(self, message: Message) -> None:
        try:
            state = ComponentState.from_payload(message.payload)
        except (KeyError, ValueError, TypeError) as e:
            log.warning("malformed state on %s: %s", message.key, e)
            return
        if self.components is not None and state.component not in self.components:
            return  # measured where it runs
        if state.state.is_alive and isinstance(state.pid, int):
            self.sampler.track(state.component, state.pid)
        else:
            self.sampler.untrack(state.component)


class ResourceSampler:
    """Samples the process trees it is told of and publishes them on ``resources`` at
    its rate (a host agent tells it of the processes it starts itself).

    Args:
        bus: where to publish.
        rate: samples per second.
        hostname: the name in each report (default: this computer's).
        key: where to publish (a host agent: ``host/<name>/resources``).
    """

    def __init__(
        self,
        bus: Bus,
        *,
        rate: float = 1.0,
        hostname: str | None = None,
        key: str = RESOURCES,
    ) -> None:
        if rate <= 0:
            raise ConfigError(f"the resource monitor's rate must be positive, not {rate:g}")
        self.bus = bus
        self.rate = rate
        self.hostname = hostname or socket.gethostname()
        self.key = key
        self._pids: dict[str, int] = {}
        self._processes: dict[int, psutil.Process] = {}
        self._lock = threading.Lock()
        self._stopped = threading.Event()
        self._thread = threading.Thread(target=self._loop, name="resource-monitor", daemon=True)

    def start(self) -> None:
        self._thread.start()

    def stop(self) -> None:
        self._stopped.set()
        if self._thread.is_alive():
            self._thread.join()

    def track(self, name: str, pid: int) -> None:
        """Measure a component's process tree from now on."""
        with self._lock:
            self._pids[name] = pid

    def untrack(self, name: str) -> None:
        with self._lock:
            self._pids.pop(name, None)

    def _loop(self) -> None:
        period = 1.0 / self.rate
        due = time.monotonic()
        while not self._stopped.wait(max(0.0, due - time.monotonic())):
            due = max(due + period, time.monotonic() - period)
            try:
                self.bus.publish(self.key, self.measure().to_payload())
            except DuraError as e:
                log.warning("cannot publish resources: %s", e)

    def measure(self) -> ResourceInfo:
        """One sample of every tracked component."""
        with self._lock:
            pids = sorted(self._pids.items())
        seen: set[int] = set()
        nodes = tuple(self._node(name, pid, seen) for name, pid in pids)
        for pid in set(self._processes) - seen:
            del self._processes[pid]
        return ResourceInfo(self.hostname, nodes, time.time())

    def _process(self, pid: int, seen: set[int]) -> psutil.Process:
        """The same psutil object for a process every time (CPU% needs the last sample)."""
        seen.add(pid)
        process = self._processes.get(pid)
        if process is None or not process.is_running():
            process = self._processes[pid] = psutil.Process(pid)
        return process

    def _node(self, name: str, pid: int, seen: set[int]) -> NodeInfo:
        try:
            root = self._process(pid, seen)
            if root.status() == psutil.STATUS_ZOMBIE:
                return NodeInfo(name, pid, self.hostname, 0.0, 0, f"process {pid} is a zombie")
            tree = [root, *root.children(recursive=True)]
        except psutil.NoSuchProcess:
            return NodeInfo(name, pid, self.hostname, 0.0, 0, f"process {pid} vanished")
        except psutil.AccessDenied:
            return NodeInfo(name, pid, self.hostname, 0.0, 0, f"process {pid}: access denied")
        cpu, memory = 0.0, 0
        for member in tree:
            try:
                process = self._process(member.pid, seen)
                with process.oneshot():
                    cpu += process.cpu_percent(None)
                    memory += process.memory_info().rss
            except (psutil.NoSuchProcess, psutil.AccessDenied):
                continue
        return NodeInfo(name, pid, self.hostname, round(cpu, 1), memory)
