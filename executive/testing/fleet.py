"""A fleet run by a real ``dura fleet run`` process, driven over the fleet's bus: for
tests, the demo and the benchmarks.

:class:`FleetProcess` starts the fleet's high level for a fleet description in a folder
of its own (its knowledge base, bus credentials and output; a free loopback endpoint)
and waits until it plans; goals, plans, facts and events are then asked of it as of a
robot (:class:`~executive.testing.client.RobotClient`). Its robots run their own
executives beside it (:class:`~executive.testing.harness.RobotProcess`), which write the
fleet's login into their folders: the fleet description names those files
(:func:`fleet_variant` writes one for the robots a test runs).
"""

from __future__ import annotations

import os
import subprocess
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import yaml

from executive.bus import security
from executive.bus.clock import SCALE_VARIABLE, Clock
from executive.testing.harness import START_TIMEOUT, ExecutiveProcess, RobotProcess, free_endpoint
from knowledge.description import RobotDescription
from knowledge.errors import DuraError
from knowledge.yamlsource import load as load_yaml


def fleet_variant(
    description: str | Path, robots: Sequence[RobotProcess], folder: Path, **changes: Any
) -> Path:
    """Write a copy of a fleet description into ``folder`` whose robots are ``robots``,
    where they run (their endpoints, and the fleet's logins their executives wrote), with
    its domain and problem paths made absolute and the top-level ``changes`` made
    (``max_failures=2``). Returns the copy's path."""
    description = Path(description).resolve()
    data = dict(load_yaml(description) or {})
    for key in ("domain", "problem"):
        if data.get(key):
            data[key] = str((description.parent / str(data[key])).resolve())
    data["robots"] = {
        r.robot.name: {
            "description": str(r.description),
            "endpoint": r.endpoint,
            "login": str(security.fleet_credentials_file(r.folder, r.robot.name).resolve()),
        }
        for r in robots
    }
    data.update(changes)
    folder.mkdir(parents=True, exist_ok=True)
    copy = folder / description.name
    copy.write_text(yaml.safe_dump(data, sort_keys=False), encoding="utf-8")
    return copy


class FleetProcess(ExecutiveProcess):
    """The high level of one fleet, as a child process.

    Args:
        description: the fleet description (``fleet.yaml``).
        folder: where its knowledge base, credentials and output (``fleet.log``) go.
        endpoint: where it listens (default: a free loopback port).
        time_scale: robot time runs this many times faster than the wall clock.
        join_wait: seconds it waits for its robots before its first plan.
    """

    def __init__(
        self,
        description: str | Path,
        folder: Path,
        endpoint: str | None = None,
        *,
        time_scale: float | None = None,
        join_wait: float = 10.0,
    ) -> None:
        self.description = Path(description).resolve()
        written = load_yaml(self.description) or {}
        name = str(written.get("fleet") or self.description.stem)
        self.robot = RobotDescription(name, self.description, self.description)
        self.clock = Clock(time_scale) if time_scale is not None else Clock.from_environment()
        self.folder = Path(folder)
        self.folder.mkdir(parents=True, exist_ok=True)
        self.endpoint = endpoint or free_endpoint()
        self.join_wait = join_wait
        self.kb_path = self.folder / f"{name}.db"
        self.output = self.folder / "fleet.log"
        super().__init__()

    @property
    def what(self) -> str:
        return f"the fleet '{self.robot.name}'"

    def start(self, timeout: float = START_TIMEOUT) -> None:
        """Start the fleet and wait until it plans (its liveliness token is there)."""
        argv = [sys.executable, "-m", "executive.cli", "fleet", "run", str(self.description),
                "--endpoint", self.endpoint, "--db", str(self.kb_path),
                "--join-wait", str(self.join_wait)]  # fmt: skip
        env = {**os.environ, **self.clock.environment()}
        if not self.clock.scaled:
            env.pop(SCALE_VARIABLE, None)
        with self.output.open("ab") as out:
            self._process = subprocess.Popen(
                argv, cwd=self.folder, stdout=out, stderr=subprocess.STDOUT, env=env
            )
        code = self._started("goal/list", timeout)
        if code is not None:
            raise DuraError(f"the fleet exited with {code} at start:\n{self.log_tail()}")
