"""``dura run --record`` and ``dura record`` on a ROS 2 robot: its ROS 2 topics recorded
as rosbag2 records them (CDR with the type's ``ros2msg`` schema), beside dura's own JSON
messages; fed by a plain DDS peer acting as a ROS 2 node."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path

from cyclonedds._clayer import ddspy_take
from cyclonedds.core import InstanceState, SampleState, ViewState
from mcap.reader import make_reader
from rosbags.typesys import Stores, get_types_from_msg, get_typestore

from executive.bags.bag import Route
from executive.bags.reader import open_bag
from executive.bags.recording import Recording
from executive.bus.api.components import COMPONENT_LIST, ComponentsReply
from executive.bus.service import Context
from executive.bus.session import Bus
from executive.ros2.link import Ros2Link
from executive.service_groups import recording_group
from knowledge.description import RobotDescription
from knowledge.errors import BagError
from tests.conftest import ROOT, ended, wait_for
from tests.executive.ros2.messages import LaserScan, ParticipantEntitiesInfo
from tests.executive.ros2.peer import RosPeer, ros_qos, streaming


def test_a_ros2_topic_is_recorded_as_cdr_with_its_ros2msg_schema(
    context: Context, link: Ros2Link, peer: RosPeer, tmp_path: Path
) -> None:
    path = tmp_path / "run.mcap"
    (recording,) = recording_group(context, path, None, link)
    assert isinstance(recording, Recording)
    writer = peer.publisher("lidar", "/scan", LaserScan)
    recording.configure()
    try:
        with streaming(writer, 20):
            assert wait_for(lambda: recording.messages >= 10)
    finally:
        recording.shutdown()
    with path.open("rb") as f:
        records = [
            (s, c, m) for s, c, m in make_reader(f).iter_messages() if c.topic == "topic/scan"
        ]
    assert len(records) >= 10
    schema, channel, first = records[0]
    assert (schema.name, schema.encoding) == ("sensor_msgs/msg/LaserScan", "ros2msg")
    assert (channel.message_encoding, channel.metadata["caller_id"]) == ("cdr", "lidar")
    store = get_typestore(Stores.EMPTY)  # rosbags, from the file's definition alone
    store.register(get_types_from_msg(schema.data.decode(), schema.name))
    decoded = store.deserialize_cdr(first.data, schema.name)
    assert decoded.header.frame_id == "laser" and list(decoded.ranges) == [1.0, 2.0, 3.0, 4.0, 5.0]
    with open_bag(path) as bag:
        replayed = next(bag.messages({"topic/scan": Route("topic/scan")}))
        assert replayed.payload["ranges"] == [1.0, 2.0, 3.0, 4.0, 5.0]


def recorded_scans(path: Path) -> int:
    """How many ``/scan`` messages a recording in progress has on disk (0: none yet)."""
    try:
        with open_bag(path) as bag:
            return sum(1 for _ in bag.messages({"topic/scan": Route("topic/scan")}))
    except BagError:  # not even its header yet
        return 0


def graph_has_node(peer: RosPeer, name: str) -> Callable[[], bool]:
    """Whether a node of that name is on ``ros_discovery_info`` (as ``ros2 node list``
    sees it)."""
    graph = peer.reader("ros_discovery_info", ParticipantEntitiesInfo, ros_qos(latched=True))
    seen: set[str] = set()

    def has() -> bool:
        any_state = SampleState.Any | ViewState.Any | InstanceState.Any
        for data, _ in ddspy_take(graph._ref, any_state, 64):
            info = ParticipantEntitiesInfo.deserialize(data)
            seen.update(n.node_name for n in info.node_entities_info_seq)
        return name in seen

    return has


def test_dura_record_records_the_robots_ros2_topics_as_cdr_from_a_node_of_its_own(
    ros2_robot: RobotDescription, bus: Bus, peer: RosPeer, tmp_path: Path
) -> None:
    COMPONENT_LIST.serve(bus, lambda _: ComponentsReply([]))  # the executive's verb
    out = tmp_path / "run.mcap"
    argv = [sys.executable, "-m", "executive.cli", "record", str(out), "--flush", "0.2"]
    argv += ["--robot", str(ros2_robot.path), "--endpoint", ros2_robot.endpoint]
    recorder = subprocess.Popen(
        argv,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env={**os.environ, "PYTHONPATH": str(ROOT), "PYTHONFAULTHANDLER": "1"},
    )  # the environment's CYCLONEDDS_URI: loopback
    try:
        assert recorder.stdout is not None
        assert recorder.stdout.readline().startswith("dura: recording robot 'monitored'")
        writer = peer.publisher("lidar", "/scan", LaserScan)
        recorder_node = graph_has_node(peer, "dura_record")
        with streaming(writer, 20):
            assert wait_for(lambda: recorded_scans(out) >= 10, 30)
            assert wait_for(recorder_node)
    finally:
        recorder.send_signal(signal.SIGINT)
        stdout, stderr = ended(recorder, 30)
    assert recorder.returncode == 0, stderr
    assert stdout.startswith("dura: recorded ") and not stderr
    with out.open("rb") as f:
        records = [(s, c, m) for s, c, m in make_reader(f).iter_messages()
                   if c.topic == "topic/scan"]  # fmt: skip
    assert len(records) >= 10
    store = get_typestore(Stores.EMPTY)  # rosbags, from the file's definition alone
    for schema, channel, message in records:
        assert (schema.name, schema.encoding) == ("sensor_msgs/msg/LaserScan", "ros2msg")
        assert (channel.message_encoding, channel.metadata["caller_id"]) == ("cdr", "lidar")
        if schema.name not in store.fielddefs:
            store.register(get_types_from_msg(schema.data.decode(), schema.name))
        decoded = store.deserialize_cdr(message.data, schema.name)
        assert decoded.header.frame_id == "laser"
        assert list(decoded.ranges) == [1.0, 2.0, 3.0, 4.0, 5.0]
        stamp = decoded.header.stamp.sec * 10**9 + decoded.header.stamp.nanosec
        assert stamp <= message.publish_time <= message.log_time  # sent, then received
