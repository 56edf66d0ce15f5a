"""dura's place in a robot's ROS 2 graph: the parts that one ``ros2:`` section needs.

A :class:`Ros2Link` opens, for a :class:`~knowledge.ros2_spec.Ros2Spec`, the robot's
message types, one DDS participant in its domain, the graph (discovery, with dura's
own node) and the topic source observers read ROS 2 topics from; it closes them in
reverse. The composition root opens one and hands its parts to the services::

    with Ros2Link(robot.ros2) as ros2:
        observers = ObserverManager(context, sources=[ros2.topics])
        state = Ros2StatePublisher(context, robot.ros2, link=ros2)
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping

from executive.ros2.discovery import Discovery
from executive.ros2.participant import Participant
from executive.ros2.topics import Ros2Topics
from executive.ros2.types import TypeLibrary
from knowledge.description import RobotDescription
from knowledge.errors import ConfigError
from knowledge.ros2_spec import Ros2Spec


class Ros2Link:
    """One participant in the robot's ROS 2 domain with its types, graph and topics.

    ``nodes`` maps the ROS 2 nodes that are components of the robot to the components'
    names: their samples carry the component's name as caller id.

    Raises:
        ConfigError: an unsupported transport or an invalid message definition.
        BusError: DDS cannot create the participant.
    """

    def __init__(self, spec: Ros2Spec, *, nodes: Mapping[str, str] | None = None) -> None:
        if spec.transport != "dds":
            raise ConfigError(f"ROS 2 transport '{spec.transport}' is not supported (only dds)")
        self.spec = spec
        self.library = TypeLibrary.of(spec)
        self.participant = Participant(spec.domain_id, name=spec.node)
        try:
            self.discovery = Discovery(
                self.participant, self.library, node=spec.node, aliases=nodes
            )
            self.topics = Ros2Topics(spec, self.participant, self.library, self.discovery)
        except BaseException:
            self.participant.close()
            raise

    @classmethod
    def of(cls, robot: RobotDescription, process: str | None = None) -> Ros2Link:
        """Open the link of a robot with a ``ros2:`` section: the executive's, or that of
        another dura process of the robot (``monitoring``, ``record``), whose node is
        named after it (``dura_monitoring``) so that ROS 2 tools tell them apart.

        Raises:
            ConfigError: the robot has no ``ros2:`` section, or see the class.
        """
        spec = robot.ros2
        if spec is None:
            raise ConfigError(f"robot '{robot.name}' has no ros2 section")
        if process is not None:
            spec = dataclasses.replace(spec, node=f"{spec.node}_{process}")
        nodes = {c.ros2.node: name for name, c in robot.components.items()
                 if c.ros2 is not None and c.ros2.node is not None}  # fmt: skip
        return cls(spec, nodes=nodes)

    def close(self) -> None:
        """Close the topics, the graph and the participant (idempotent)."""
        if self.participant.closed:
            return
        self.topics.close()
        self.discovery.close()
        self.participant.close()

    def __enter__(self) -> Ros2Link:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
