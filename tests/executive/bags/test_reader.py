"""Recordings read as bus messages: rosbag2 in MCAP and sqlite3 written by ``rosbags``,
MCAP files with publish times, topics routed to a robot's, and bad recordings refused."""

from __future__ import annotations

import contextlib
import shutil
import sqlite3
from pathlib import Path

import pytest
from mcap.writer import Writer as McapWriter

from executive.bags.bag import Route, routes
from executive.bags.reader import open_bag, read_types
from knowledge.description import RobotDescription
from knowledge.errors import BagError, BusError
from knowledge.robot import load_robot
from monitoring.replay import Replay
from tests.conftest import USECASE
from tests.executive.bags.recorded import (
    SCAN,
    SWEEP,
    T0,
    TYPES,
    scan,
    scan_times,
    write_mcap,
    write_scan_bag,
    write_unknown_type_bag,
)


@pytest.fixture(scope="module")
def robot() -> RobotDescription:
    return load_robot(USECASE)


@pytest.mark.parametrize("storage", ["mcap", "sqlite3"])
def test_a_rosbag2_is_read_as_bus_messages_with_the_bags_times_and_decoded_payloads(
    tmp_path: Path, robot: RobotDescription, storage: str
) -> None:
    with open_bag(write_scan_bag(tmp_path / "bag", storage)) as bag:
        assert bag.format == f"rosbag2 ({storage})"
        assert (bag.start, bag.end, bag.count) == (T0, T0 + 19.9, 180)
        found = routes(bag, robot)
        assert found == {"/scan": Route("topic/scan", "lidar")}  # the only publisher of scan
        messages = list(bag.messages(found))
    assert [m.received for m in messages] == [t / 1e9 for t in scan_times()]
    first = messages[0]
    assert (first.key, first.caller_id) == ("topic/scan", "lidar")
    assert first.sent == (T0 if storage == "mcap" else None)  # sqlite3 has no publish time
    assert first.stamp == T0  # header.stamp
    assert first.payload["ranges"][:2] == [2.0, 2.0]
    assert first.payload["header"]["frame_id"] == "laser"


def test_a_window_yields_only_the_messages_in_it(tmp_path: Path, robot: RobotDescription) -> None:
    with open_bag(write_scan_bag(tmp_path / "bag")) as bag:
        messages = list(bag.messages(routes(bag, robot), (T0 + 1) * 10**9, (T0 + 2) * 10**9))
    assert [round(m.received - T0, 3) for m in messages] == [1.0 + k / 10 for k in range(11)]


def test_publish_times_are_the_send_times_the_frequency_observer_measures(
    tmp_path: Path, robot: RobotDescription
) -> None:
    # sent at 10 Hz, received in bursts of five every half second
    records = [(T0 * 10**9 + (k // 5 + 1) * 5 * 10**8, T0 * 10**9 + k * 10**8) for k in range(60)]
    with open_bag(write_mcap(tmp_path / "jazzy.mcap", records)) as bag:
        messages = list(bag.messages(routes(bag, robot)))
    assert messages[3].sent == T0 + 0.3 and messages[3].received == T0 + 0.5
    timeline = Replay(robot, provided={"topic/scan"}, origin_ns=T0 * 10**9).run(messages)
    frequency = timeline.observations("lidar/0")[0]
    assert frequency.values["frequency"] == pytest.approx(10.0)


def test_a_caller_id_recorded_on_the_channel_is_the_messages_caller(
    tmp_path: Path, robot: RobotDescription
) -> None:
    records = [(T0 * 10**9 + k * 10**8,) * 2 for k in range(3)]
    path = write_mcap(tmp_path / "s.mcap", records, metadata={"caller_id": "front_lidar"})
    with open_bag(path) as bag:
        assert bag.topics[0].callers == ("front_lidar",)
        assert {m.caller_id for m in bag.messages(routes(bag, robot))} == {"front_lidar"}


def test_a_map_routes_a_recorded_topic_to_a_topic_of_the_robot(
    tmp_path: Path, robot: RobotDescription
) -> None:
    with open_bag(write_scan_bag(tmp_path / "bag", topic="/front/scan")) as bag:
        with pytest.raises(
            BagError, match=r"none of its topics \(/front/scan\) is a topic of robot 'usecase'"
        ):
            routes(bag, robot)
        assert routes(bag, robot, ["/front/scan=scan"]) == {
            "/front/scan": Route("topic/scan", "lidar")
        }
        with pytest.raises(
            BagError, match=r"no topic '/front/scna' to map \(did you mean '/front/scan'\?\)"
        ):
            routes(bag, robot, ["/front/scna=scan"])
        with pytest.raises(
            BagError, match=r"--map /front/scan=scna: robot 'usecase' has no topic 'scna'"
        ):
            routes(bag, robot, ["/front/scan=scna"])
        with pytest.raises(BagError, match=r"--map /front/scan: write BAG_TOPIC=TOPIC"):
            routes(bag, robot, ["/front/scan"])


def test_a_humble_bag_without_definitions_reads_its_types_from_the_type_store(
    tmp_path: Path, robot: RobotDescription
) -> None:
    path = write_scan_bag(tmp_path / "bag", "sqlite3", version=8)
    (database,) = path.glob("*.db3")
    with contextlib.closing(sqlite3.connect(database)) as db, db:
        db.execute("DELETE FROM message_definitions")
    with open_bag(path) as bag:
        first = next(bag.messages(routes(bag, robot)))
    assert first.payload["scan_time"] == pytest.approx(0.1)


def test_a_type_that_neither_the_bag_nor_the_store_defines_gives_times_and_is_noted_once_when_decoded(
    tmp_path: Path, robot: RobotDescription
) -> None:
    path = write_unknown_type_bag(tmp_path / "bag")
    with open_bag(path) as bag:
        messages = list(bag.messages(routes(bag, robot)))
        assert [m.received for m in messages] == [T0 + k / 10 for k in range(10)]
        assert bag.notes == []  # nothing decoded yet
        for message in messages:
            with pytest.raises(BusError, match="acme_msgs/msg/Sweep"):
                _ = message.payload
    assert bag.notes == [
        f"{path}: topic '/scan' not decoded: its type 'acme_msgs/msg/Sweep' is unknown (the "
        "bag does not define it, rosbags' latest types do not know it; --types DIR reads "
        ".msg files)"
    ]


def test_types_from_msg_and_idl_files_decode_what_the_bag_does_not_define(
    tmp_path: Path, robot: RobotDescription
) -> None:
    (tmp_path / "types" / "acme_msgs" / "msg").mkdir(parents=True)
    (tmp_path / "types" / "acme_msgs" / "msg" / "Sweep.msg").write_text(SWEEP)
    path = write_unknown_type_bag(tmp_path / "bag")
    with open_bag(path, read_types([tmp_path / "types"])) as bag:
        angles = [m.payload["angle"] for m in bag.messages(routes(bag, robot))]
    assert angles == [float(k) for k in range(10)]
    idl = tmp_path / "idl" / "Sweep.idl"
    idl.parent.mkdir()
    idl.write_text(
        "module acme_msgs { module msg { struct Sweep { float angle; }; }; };\n"
    )  # as rosidl writes it for Sweep.msg
    with open_bag(path, read_types([tmp_path / "idl"])) as bag:
        assert [m.payload["angle"] for m in bag.messages(routes(bag, robot))] == angles
    idl.write_text("module acme_msgs { struct")
    with pytest.raises(BagError, match=r"^--types: .*Sweep\.idl: cannot read it"):
        read_types([tmp_path / "idl"])
    (tmp_path / "types" / "acme_msgs" / "msg" / "Sweep.msg").write_text("floot32 angle\n")
    with pytest.raises(BagError, match=r"^--types: .*Sweep\.msg:1: "):
        read_types([tmp_path / "types"])


def test_an_mcap_channel_without_a_schema_gives_times_and_cannot_be_decoded(
    tmp_path: Path, robot: RobotDescription
) -> None:
    path = write_mcap(tmp_path / "s.mcap", [(T0 * 10**9, T0 * 10**9)], schema=False)
    with open_bag(path) as bag:
        (message,) = bag.messages(routes(bag, robot))
        assert message.received == T0
        with pytest.raises(BusError, match=r"its type '\?' is unknown"):
            _ = message.payload


def test_an_empty_mcap_schema_is_a_message_without_fields(
    tmp_path: Path, robot: RobotDescription
) -> None:
    empty = "test_msgs/msg/Empty"
    raw = bytes(TYPES.serialize_cdr(TYPES.types["std_msgs/msg/Empty"](), "std_msgs/msg/Empty"))
    path = tmp_path / "e.mcap"
    with path.open("wb") as stream:
        writer = McapWriter(stream)
        writer.start(profile="ros2", library="tests")
        channel = writer.register_channel(
            "/scan", "cdr", writer.register_schema(empty, "ros2msg", b"")
        )
        writer.add_message(channel, T0 * 10**9, raw, T0 * 10**9)
        writer.finish()
    with open_bag(path) as bag:
        (message,) = bag.messages(routes(bag, robot))
        assert message.payload == {"structure_needs_at_least_one_member": 0}
    assert bag.notes == []


def truncated(source: Path, target: Path, keep: float) -> Path:
    data = source.read_bytes()
    target.write_bytes(data[: int(len(data) * keep)])
    return target


def test_a_truncated_database_is_an_error_naming_it(tmp_path: Path) -> None:
    (source,) = write_scan_bag(tmp_path / "bag", "sqlite3").glob("bag.*")
    cut = truncated(source, tmp_path / f"cut{source.suffix}", 0.6)
    with pytest.raises(BagError, match=f"^{cut}: truncated or corrupt"):
        open_bag(cut)


def test_an_mcap_file_cut_before_its_first_chunk_ends_is_read_empty_and_says_so(
    tmp_path: Path,
) -> None:
    (source,) = write_scan_bag(tmp_path / "bag", "mcap").glob("bag.*")
    cut = truncated(source, tmp_path / "cut.mcap", 0.6)
    with open_bag(cut) as bag:
        assert bag.count == 0
        (note,) = bag.notes
    assert note.startswith(f"{cut}: cut off (no summary: the recording did not end): read 0")
    cut.write_bytes(source.read_bytes()[:12])  # the magic, and not all of the header
    with pytest.raises(BagError, match=f"^{cut}: truncated or corrupt MCAP"):
        open_bag(cut)


def test_a_corrupt_chunk_is_an_error_naming_the_file(
    tmp_path: Path, robot: RobotDescription
) -> None:
    records = [(t, t) for t in scan_times()]
    source = write_mcap(tmp_path / "scan.mcap", records)  # chunks compressed with zstd
    data = bytearray(source.read_bytes())
    middle = len(data) // 3
    data[middle : middle + 64] = bytes(64)  # zeros inside a compressed chunk
    corrupt = tmp_path / "corrupt.mcap"
    corrupt.write_bytes(bytes(data))
    with (
        pytest.raises(BagError, match=f"^{corrupt}: truncated or corrupt"),
        open_bag(corrupt) as bag,  # the first and last messages are read when opened
    ):
        list(bag.messages(routes(bag, robot)))


def test_what_is_not_a_recording_is_refused(tmp_path: Path) -> None:
    (tmp_path / "notes.txt").write_text("hello")
    with pytest.raises(BagError, match=r"notes\.txt: not a ROS 2 bag or an MCAP file"):
        open_bag(tmp_path / "notes.txt")
    with pytest.raises(BagError, match="not a rosbag2 folder"):
        open_bag(tmp_path)
    shutil.rmtree(tmp_path)
    with pytest.raises(BagError, match="cannot read it"):
        open_bag(tmp_path / "gone.mcap")


def test_a_bag_split_into_several_mcap_files_is_read_as_one_in_order(
    tmp_path: Path, robot: RobotDescription
) -> None:
    folder = tmp_path / "split"
    folder.mkdir()
    times = scan_times(None, 2.0)
    write_mcap(folder / "split_0.mcap", [(t, t) for t in times[:12]])
    write_mcap(folder / "split_1.mcap", [(t, t) for t in times[12:]])
    (folder / "metadata.yaml").write_text(
        "rosbag2_bagfile_information:\n  version: 9\n  storage_identifier: mcap\n"
        "  relative_file_paths: [split_0.mcap, split_1.mcap]\n  ros_distro: jazzy\n"
    )
    with open_bag(folder) as bag:
        assert (bag.format, bag.count) == ("rosbag2 (mcap)", 20)
        received = [m.received for m in bag.messages(routes(bag, robot))]
    assert received == [t / 1e9 for t in times]
    (folder / "split_1.mcap").unlink()
    with pytest.raises(BagError, match=r"files of the bag are missing: .*split_1\.mcap"):
        open_bag(folder)


def test_split_mcap_files_that_number_their_channels_differently_are_read_as_one(
    tmp_path: Path, robot: RobotDescription
) -> None:
    folder = tmp_path / "split"
    folder.mkdir()
    text, _ = TYPES.generate_msgdef(SCAN, ros_version=2)
    times = scan_times(None, 2.0)
    for index, (topics, part) in enumerate(
        [(["/scan", "/other"], times[:10]), (["/other", "/scan"], times[10:])]
    ):
        with (folder / f"split_{index}.mcap").open("wb") as stream:  # as rosbag2 splits
            writer = McapWriter(stream)
            writer.start(profile="ros2", library="tests")
            schema = writer.register_schema(SCAN, "ros2msg", text.encode())
            ids = {name: writer.register_channel(name, "cdr", schema) for name in topics}
            for t in part:
                writer.add_message(ids["/scan"], t, scan(t), t)
                writer.add_message(ids["/other"], t + 1, scan(t), t)
            writer.finish()
    (folder / "metadata.yaml").write_text(
        "rosbag2_bagfile_information:\n  version: 9\n  storage_identifier: mcap\n"
        "  relative_file_paths: [split_0.mcap, split_1.mcap]\n"
    )
    with open_bag(folder) as bag:
        assert bag.count == 40
        received = [m.received for m in bag.messages(routes(bag, robot))]
    assert received == [t / 1e9 for t in times]  # /scan only, from both files
