"""The host agent's process (``dura host``): its bus login, its launcher and the
resource monitor of its own processes, composed (as :mod:`executive.executive` composes
the executive's)."""

from __future__ import annotations

import threading
from collections.abc import Callable
from pathlib import Path

from executive.bus import security
from executive.bus.session import Bus
from executive.runtime.host_agent import HostAgent
from knowledge.description import RobotDescription
from monitoring.resource_monitor import ResourceSampler


def run_host(
    robot: RobotDescription,
    name: str,
    *,
    endpoint: str,
    stop: threading.Event,
    folder: Path,
    credentials: Path | None = None,
    log_dir: Path | None = None,
    grace: float = 3.0,
    resource_rate: float = 1.0,
    lease: float | None = None,
    say: Callable[[str], None] = lambda line: None,
) -> None:
    """Run the agent of host ``name`` until ``stop`` is set.

    Raises:
        BusError: no usable credentials for the host.
        ComponentError: the robot places nothing on that host.
    """
    login = security.find_host_login(robot.name, name, folder, credentials)

    def sampler(bus: Bus) -> ResourceSampler:
        return ResourceSampler(bus, rate=resource_rate, hostname=name)

    agent = HostAgent(
        robot,
        name,
        endpoint=endpoint,
        login=login,
        log_dir=log_dir or folder / ".dura" / "logs",
        grace=grace,
        tracker=sampler,
        lease=lease,
        say=say,
    )
    agent.run(stop)
