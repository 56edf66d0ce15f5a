"""A dura recording's ROS 2 topics as a rosbag2 bag that ``rosbags`` opens with its own
readers (``AnyReader``, the rosbag2 ``Reader``), dura's JSON channels left in the
recording; ``dura record --ros2-bag`` as a user runs it."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest
from rosbags.highlevel import AnyReader
from rosbags.rosbag2 import Reader, ReaderError
from rosbags.typesys import Stores, get_typestore

from executive.bags.export import export_ros2
from executive.bags.recording import Recorder
from executive.bus.keys import OBSERVATIONS, topic
from executive.bus.message import Message, encode
from executive.ros2.message import RosMessage
from knowledge.errors import BagError
from tests.executive.bags.recorded import SCAN, scan, write_scan_bag

STORE = get_typestore(Stores.ROS2_JAZZY)
T0_NS = 1_700_000_000_046_666_662
TIMES = [T0_NS + k * 100_000_001 for k in range(30)]


def record(path: Path) -> Path:
    """A recording of two lidars on /scan, a battery on /robot1/battery (another type),
    and dura's own observations."""
    with Recorder(
        path, "usecase", ros2_definition=lambda t: STORE.generate_msgdef(t, ros_version=2)[0]
    ) as recorder:
        for k, t in enumerate(TIMES):
            caller = "lidar" if k % 2 else "lidar2"
            recorder.write(RosMessage.at_ns(topic("scan"), scan(t), caller, t - 5, t, type=SCAN))
            if k % 10 == 0:
                level = battery(80.0 - k)
                kind = "std_msgs/msg/Float64"
                recorder.write(RosMessage.at_ns(topic("robot1/battery"), level, "battery", None,
                                                t + 1, type=kind))  # fmt: skip
                observed = encode({"observer": "lidar/0", "stamp": t / 1e9})
                recorder.write(Message.at_ns(OBSERVATIONS, observed, "executive", None, t + 2))
    return path


def battery(level: float) -> bytes:
    kind = "std_msgs/msg/Float64"
    return bytes(STORE.serialize_cdr(STORE.types[kind](data=level), kind))


def test_the_ros2_topics_of_a_recording_are_a_bag_that_rosbags_own_readers_open(
    tmp_path: Path,
) -> None:
    path, out = record(tmp_path / "run.mcap"), tmp_path / "run_ros2"
    with pytest.raises(ReaderError, match="Profile is not ros2"), Reader(path):
        pass  # why there is an export: the recording itself is of profile dura
    exported = export_ros2(path, out)
    assert exported.topics == ("/robot1/battery", "/scan")
    assert exported.messages == 33
    assert exported.left == (OBSERVATIONS,)  # dura's own, in JSON: left in the recording
    with Reader(out) as reader:  # rosbags' rosbag2 reader: metadata.yaml and the MCAP file
        assert {c.topic: c.msgtype for c in reader.connections} == {
            "/scan": SCAN,
            "/robot1/battery": "std_msgs/msg/Float64",
        }
        assert reader.message_count == 33
    with AnyReader([out]) as reader:  # types from the bag's own definitions
        scans = [c for c in reader.connections if c.topic == "/scan"]
        read = [(t, reader.deserialize(raw, c.msgtype)) for c, t, raw in reader.messages(scans)]
    assert [t for t, _ in read] == TIMES  # the recorded receive times, to the ns
    stamps = [m.header.stamp.sec * 10**9 + m.header.stamp.nanosec for _, m in read]
    assert stamps == TIMES
    assert all(m.header.frame_id == "laser" for _, m in read)


def test_only_a_dura_recording_is_exported_and_never_over_a_folder(tmp_path: Path) -> None:
    bag = write_scan_bag(tmp_path / "ros", "mcap")
    with pytest.raises(BagError, match="not a dura recording"):
        export_ros2(next(bag.glob("*.mcap")), tmp_path / "out")
    assert not (tmp_path / "out").exists()
    (tmp_path / "taken").mkdir()
    with pytest.raises(BagError, match="exists already"):
        export_ros2(record(tmp_path / "run.mcap"), tmp_path / "taken")


def test_dura_record_ros2_bag_writes_the_bag_and_says_so_in_one_line(tmp_path: Path) -> None:
    path = record(tmp_path / "run.mcap")
    command = [sys.executable, "-m", "executive.cli", "record", "--ros2-bag", str(path)]
    result = subprocess.run([*command, "--json"], capture_output=True, text=True, check=True)
    assert json.loads(result.stdout) == {
        "path": str(tmp_path / "run_ros2"),
        "topics": ["/robot1/battery", "/scan"],
        "messages": 33,
        "left": [OBSERVATIONS],
    }
    again = subprocess.run(command, check=False, capture_output=True, text=True)
    assert again.returncode == 1
    folder = tmp_path / "run_ros2"
    assert again.stderr == f"dura: {folder}: exists already (the bag is written to a new folder)\n"


def test_a_recording_cut_off_by_a_crash_exports_up_to_its_last_whole_chunk(
    tmp_path: Path,
) -> None:
    path = tmp_path / "cut.mcap"
    recorder = Recorder(
        path, "usecase", ros2_definition=lambda t: STORE.generate_msgdef(t, ros_version=2)[0]
    )
    whole = 0
    for k, t in enumerate(TIMES):
        recorder.write(RosMessage.at_ns(topic("scan"), scan(t), "lidar", None, t, type=SCAN))
        if k % 10 == 9:
            recorder.flush()  # a whole chunk on disk
            whole = path.stat().st_size if k < 20 else whole
    recorder.close()
    path.write_bytes(path.read_bytes()[: whole + 40])  # the third chunk cut, no summary
    exported = export_ros2(path, tmp_path / "out")
    with AnyReader([tmp_path / "out"]) as reader:
        times = [t for _, t, _ in reader.messages()]
    assert exported.messages == len(times) == 20
    assert times == TIMES[:20]
