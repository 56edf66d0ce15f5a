"""The ROS 2 graph from discovery: node names, who publishes and subscribes what, and dura
as a node of the graph; also across processes, over real UDP on loopback."""

from __future__ import annotations

import json
import logging
import subprocess
import sys
from typing import Any

import pytest
from cyclonedds._clayer import ddspy_take, ddspy_write
from cyclonedds.core import InstanceState, SampleState, ViewState

from executive.bus.message import Message
from executive.ros2.link import Ros2Link
from tests.conftest import ROOT, wait_for
from tests.executive.ros2.messages import (
    Gid,
    LaserScan,
    NodeEntitiesInfo,
    ParticipantEntitiesInfo,
    Twist,
)
from tests.executive.ros2.peer import RosPeer, ros_qos, streaming


def test_the_graph_names_each_node_with_the_topics_it_publishes_and_subscribes(
    link: Ros2Link, peer: RosPeer
) -> None:
    peer.publisher("lidar", "/scan", LaserScan)
    peer.subscriber("planner", "/scan", LaserScan, namespace="/robot1")
    peer.publisher("planner", "/cmd_vel", Twist, namespace="/robot1")
    peer.publisher("planner", "/rosout", LaserScan, namespace="/robot1")
    peer.node("idle")
    assert wait_for(lambda: "/idle" in link.discovery.nodes())  # the last announced
    nodes = link.discovery.nodes()
    assert nodes["/lidar"].publishes == ("/scan",) and nodes["/lidar"].subscribes == ()
    assert nodes["/robot1/planner"].publishes == ("/cmd_vel",)
    assert nodes["/robot1/planner"].subscribes == ("/scan",)
    assert nodes["/idle"].publishes == nodes["/idle"].subscribes == ()
    assert "/rosout" in link.discovery.nodes(everything=True)["/robot1/planner"].publishes
    assert link.discovery.types_of("/scan") == {"sensor_msgs::msg::dds_::LaserScan_"}


def test_a_sample_carries_its_nodes_name_and_dura_shows_in_the_graph_with_what_it_reads(
    link: Ros2Link, peer: RosPeer
) -> None:
    writer = peer.publisher("lidar", "/robot1/scan", LaserScan, namespace="/robot1")
    heard: list[Message] = []
    subscription = link.topics.subscribe("topic/robot1/scan", heard.append)
    graph = peer.reader("ros_discovery_info", ParticipantEntitiesInfo, ros_qos(latched=True))

    def dura_reads_scan() -> bool:
        any_state = SampleState.Any | ViewState.Any | InstanceState.Any
        for data, _ in ddspy_take(graph._ref, any_state, 64):
            info = ParticipantEntitiesInfo.deserialize(data)
            for node in info.node_entities_info_seq:
                topics = [link.discovery.node_of(bytes(g.data)) for g in node.reader_gid_seq]
                if node.node_name == "dura" and topics == ["/dura"]:
                    return True
        return False

    assert wait_for(dura_reads_scan)
    with streaming(writer, 50):
        assert wait_for(lambda: len(heard) >= 5)
    assert {m.caller_id for m in heard} == {"robot1/lidar"}
    assert link.discovery.nodes()["/dura"].subscribes == ("/robot1/scan",)
    subscription.undeclare()
    assert wait_for(lambda: link.discovery.nodes()["/dura"].subscribes == ())


def test_a_process_that_leaves_takes_its_nodes_out_of_the_graph(
    link: Ros2Link, domain: int
) -> None:
    with RosPeer(domain) as passing:
        passing.publisher("camera", "/image", LaserScan)
        assert wait_for(lambda: "/camera" in link.discovery.nodes())
    assert wait_for(lambda: "/camera" not in link.discovery.nodes())


def test_a_ros2_process_elsewhere_is_heard_over_udp_with_its_node_name(
    link: Ros2Link, domain: int
) -> None:
    plan: dict[str, Any] = {"streams": [{"node": "lidar", "topic": "/scan", "rate": 50}]}
    process = subprocess.Popen(
        [sys.executable, "-m", "tests.executive.ros2.peer", str(domain), json.dumps(plan)],
        stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True, cwd=ROOT,
    )  # fmt: skip
    heard: list[Message] = []
    try:
        assert process.stdout is not None and process.stdout.readline().strip() == "ready"
        subscription = link.topics.subscribe("topic/scan", heard.append)
        assert wait_for(lambda: len(heard) >= 20, timeout=10)
        subscription.undeclare()
    finally:
        assert process.stdin is not None
        process.stdin.close()
        assert process.wait(10) == 0
        assert process.stdout is not None
        process.stdout.close()
    assert heard[-1].caller_id == "lidar"
    assert heard[-1].payload["ranges"] == [1.0, 2.0, 3.0, 4.0, 5.0]
    assert heard[-1].sent is not None and 0 <= heard[-1].received - heard[-1].sent < 1.0
    # the peer deleted its participant before it exited: gone at once, not after a lease
    assert wait_for(lambda: "/lidar" not in link.discovery.nodes(), timeout=2)


def test_a_malformed_discovery_sample_is_one_warning_and_the_graph_stays(
    link: Ros2Link, peer: RosPeer, caplog: pytest.LogCaptureFixture
) -> None:
    peer.publisher("lidar", "/scan", LaserScan)
    assert wait_for(lambda: "/lidar" in link.discovery.nodes())
    bad = (
        ParticipantEntitiesInfo(
            gid=Gid(data=list(peer.participant.guid.bytes)),
            node_entities_info_seq=[NodeEntitiesInfo(node_name="lidar")],
        )
        .serialize()
        .replace(b"lidar\x00", b"\xffidar\x00")
    )  # valid CDR, not UTF-8
    with caplog.at_level(logging.WARNING, logger="dura.ros2"):
        ddspy_write(peer._info._ref, bad)
        assert wait_for(lambda: caplog.records)
    [warning] = caplog.records
    assert warning.getMessage().startswith("ignored a malformed ros_discovery_info sample: ")
    assert warning.exc_info is None
    assert "/lidar" in link.discovery.nodes()
