"""A component that is a ROS 2 node: its topics in the diagnosis model come from ROS 2
discovery, and its samples carry the component's name as caller id."""

from __future__ import annotations

import dataclasses
from collections.abc import Iterator

import pytest

from executive.bus.api.monitoring import DIAGNOSIS_MODEL_CHANGE, ModelChange
from executive.bus.keys import component
from executive.bus.message import Message
from executive.bus.payloads import ComponentState
from executive.bus.service import Context
from executive.bus.states import Lifecycle
from executive.ros2.graph_model import Ros2GraphModel, observed
from executive.ros2.link import Ros2Link
from knowledge.description import RobotDescription
from knowledge.ros2_components import Ros2ComponentSpec
from monitoring.diagnosis.diagnosis_service import DiagnosisService
from tests.conftest import wait_for
from tests.executive.ros2.messages import LaserScan, Twist
from tests.executive.ros2.peer import RosPeer, streaming


@pytest.fixture
def node_robot(ros2_robot: RobotDescription) -> RobotDescription:
    """The test robot whose lidar and robot_base are ROS 2 nodes (listing no topics)."""
    lidar = dataclasses.replace(
        ros2_robot.functionalities["lidar"], publishes=(), ros2=Ros2ComponentSpec("/lidar")
    )
    base = dataclasses.replace(
        ros2_robot.functionalities["robot_base"],
        publishes=("odom",),  # listed, and kept beside what the graph says
        ros2=Ros2ComponentSpec("/robot1/base"),
    )
    return dataclasses.replace(
        ros2_robot,
        functionalities={**ros2_robot.functionalities, "lidar": lidar, "robot_base": base},
    )


@pytest.fixture
def graph(node_robot: RobotDescription, context: Context, link: Ros2Link) -> Iterator[Context]:
    own = Context(node_robot, context.bus, context.kb)
    diagnosis = DiagnosisService(own, learn=True)
    model = Ros2GraphModel(own, link.discovery)
    diagnosis.configure()
    diagnosis.activate()
    model.configure()
    model.activate()
    try:
        yield own
    finally:
        model.shutdown()
        diagnosis.shutdown()


def model_nodes(context: Context) -> dict[str, tuple[list[str], list[str]]]:
    reply = DIAGNOSIS_MODEL_CHANGE.call(context.bus, ModelChange("GET"))
    nodes = (reply.model or {}).get("nodes", [])
    return {n["name"]: (sorted(n["sub_topic"]), sorted(n["pub_topic"])) for n in nodes}


def ready(context: Context, name: str) -> None:
    """Do what the task executor and the launcher do when a component is ready."""
    node = {"name": name, "sub_topic": [], "pub_topic": []}
    assert DIAGNOSIS_MODEL_CHANGE.call(context.bus, ModelChange("ADD", nodes=[node])).ok
    state = ComponentState(name, Lifecycle.READY)
    context.bus.publish(component(name, "state"), state.to_payload())


def test_a_ros2_nodes_topics_in_the_diagnosis_model_come_from_discovery(
    graph: Context, peer: RosPeer
) -> None:
    peer.publisher("lidar", "/scan", LaserScan)
    peer.publisher("lidar", "/navigate/_action/feedback", LaserScan)  # hidden
    peer.subscriber("base", "/cmd_vel", Twist, namespace="/robot1")
    peer.publisher("base", "/robot1/imu", LaserScan, namespace="/robot1")
    ready(graph, "lidar")
    ready(graph, "robot_base")
    expected = {"lidar": ([], ["scan"]), "robot_base": (["cmd_vel"], ["odom", "robot1/imu"])}
    assert wait_for(lambda: model_nodes(graph) == expected)
    peer.subscriber("lidar", "/lidar/config", Twist)  # the graph changes: so does the model
    assert wait_for(lambda: model_nodes(graph)["lidar"] == (["lidar/config"], ["scan"]))


def test_a_component_s_node_publishes_under_the_component_s_name(
    ros2_robot: RobotDescription, peer: RosPeer
) -> None:
    assert ros2_robot.ros2 is not None
    heard: list[Message] = []
    with Ros2Link(ros2_robot.ros2, nodes={"/robot1/scan_driver": "lidar"}) as link:
        subscription = link.topics.subscribe("topic/scan", heard.append)
        with streaming(peer.publisher("scan_driver", "/scan", LaserScan, namespace="/robot1"), 50):
            assert wait_for(lambda: len(heard) >= 5)
        subscription.undeclare()
    assert {m.caller_id for m in heard} == {"lidar"}


def test_hidden_topics_are_left_out_and_names_lose_their_leading_slash() -> None:
    assert observed(("/scan", "/a/_action/status", "/_hidden", "/robot1/imu")) == [
        "scan", "robot1/imu",
    ]  # fmt: skip
