"""``dura run --record`` on a ROS 2 robot: its ROS 2 topics recorded as rosbag2 records
them (CDR with the type's ``ros2msg`` schema), beside dura's own JSON messages; fed by
a plain DDS peer acting as a ROS 2 node."""

from __future__ import annotations

from pathlib import Path

from mcap.reader import make_reader
from rosbags.typesys import Stores, get_types_from_msg, get_typestore

from executive.bags.bag import Route
from executive.bags.reader import open_bag
from executive.bags.recording import Recording
from executive.bus.service import Context
from executive.ros2.link import Ros2Link
from executive.service_groups import recording_group
from tests.conftest import wait_for
from tests.executive.ros2.messages import LaserScan
from tests.executive.ros2.peer import RosPeer, streaming


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
