"""How the launcher starts a component that is a ROS 2 program: under a host of dura's.

A component with a ``ros2:`` key (:mod:`knowledge.ros2_components`) does not run its
command directly: the launcher runs :mod:`executive.runtime.ros2_host`, an SDK
component that takes dura's lifecycle commands, runs the command as its child (in
the robot's ROS 2 domain: ``ROS_DOMAIN_ID``) and carries the commands to it as ROS 2
understands them. What the host needs to know travels as JSON in ``DURA_ROS2``.

This module imports nothing of ROS 2: the launcher stays light.
"""

from __future__ import annotations

import json
from collections.abc import Mapping
from dataclasses import asdict, dataclass, field
from typing import Any

from knowledge.description import ComponentSpec, RobotDescription
from knowledge.errors import ConfigError

HOST_MODULE = "executive.runtime.ros2_host"
ENV_CONFIG = "DURA_ROS2"
ENV_DOMAIN = "ROS_DOMAIN_ID"  # what every ROS 2 program joins


@dataclass(frozen=True)
class HostConfig:
    """What a host needs to know of its component's ROS 2 side."""

    domain_id: int
    distribution: str
    messages: list[str] = field(default_factory=list)  # folders or files of definitions
    node: str | None = None  # the program's node, fully qualified
    lifecycle: bool = False
    call: dict[str, Any] | None = None  # kind, name, type, wait
    startup_timeout: float = 10.0

    def to_json(self) -> str:
        return json.dumps(asdict(self))

    @classmethod
    def from_json(cls, text: str) -> HostConfig:
        """Read the configuration the launcher wrote.

        Raises:
            ConfigError: not a host configuration.
        """
        try:
            data = json.loads(text)
            return cls(**data)
        except (ValueError, TypeError) as e:
            raise ConfigError(f"{ENV_CONFIG} is not a ROS 2 host configuration: {e}") from e


def host_config(robot: RobotDescription, spec: ComponentSpec) -> HostConfig | None:
    """Describe a component's ROS 2 side for its host (``None``: not a ROS 2 component)."""
    ros2 = spec.ros2
    if ros2 is None or robot.ros2 is None:
        return None
    call = ros2.call
    return HostConfig(
        domain_id=robot.ros2.domain_id,
        distribution=robot.ros2.distribution,
        messages=[str(p) for p in robot.ros2.messages],
        node=ros2.node,
        lifecycle=ros2.lifecycle,
        call=None
        if call is None
        else {
            "kind": call.kind,
            "name": call.name,
            "type": call.type,
            "wait": call.wait,
        },
        startup_timeout=spec.startup_timeout,
    )


def launch_program(
    robot: RobotDescription, spec: ComponentSpec
) -> tuple[list[str], Mapping[str, str]]:
    """Return the argv that starts a component and what its environment needs besides."""
    config = host_config(robot, spec)
    if config is None:
        return list(spec.command), {}
    argv = ["python", "-m", HOST_MODULE, "--", *spec.command]
    return argv, {ENV_CONFIG: config.to_json(), ENV_DOMAIN: str(config.domain_id)}
