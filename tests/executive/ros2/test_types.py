"""ROS 2 message types: dura's CDR is byte for byte rosbags', and its decoder reads rosbags'.

rosbags' serialiser is the independent reference: every message dura builds must
serialise to exactly the bytes rosbags makes of the same message, and dura must decode
what rosbags writes (both byte orders) to the values in it.
"""

from __future__ import annotations

import random
import struct
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from rosbags.interfaces import Nodetype

from executive.ros2.cdr import CdrError
from executive.ros2.discovery import gid_layouts, read_entities_info
from executive.ros2.types import TypeLibrary
from knowledge.errors import ConfigError
from knowledge.ros2_messages import message_store, standard_store
from tests.executive.ros2 import messages as by_hand

INTS = {
    "int8": 8, "uint8": 8, "byte": 8, "char": 8, "int16": 16, "uint16": 16,
    "int32": 32, "uint32": 32, "int64": 64, "uint64": 64,
}  # fmt: skip


@pytest.fixture(scope="module")
def jazzy() -> TypeLibrary:
    return TypeLibrary(standard_store("jazzy"), "jazzy")


def random_value(library: TypeLibrary, desc: tuple[Any, Any], rng: random.Random) -> Any:
    """A random value of a field (floats that float32 holds exactly)."""
    kind, details = desc
    if kind == Nodetype.BASE:
        base, bound = details
        if base == "bool":
            return rng.random() < 0.5
        if base == "string":
            return "".join(rng.choice("abé/ ") for _ in range(rng.randint(0, bound or 6)))
        if base.startswith("float"):
            return struct.unpack("f", struct.pack("f", rng.uniform(-9, 9)))[0]
        bits = INTS[base]
        low = -(2 ** (bits - 1)) if base.startswith("int") else 0
        return rng.randint(low, low + 2**bits - 1)
    if kind == Nodetype.NAME:
        return {f: random_value(library, d, rng) for f, d in library.fields(details)}
    inner, size = details
    count = size if kind == Nodetype.ARRAY else rng.randint(0, size or 3)
    return [random_value(library, inner, rng) for _ in range(count)]


@pytest.mark.parametrize("distribution", ["humble", "jazzy"])
def test_every_standard_type_serialises_as_rosbags_does_and_decodes_back(distribution: str) -> None:
    library = TypeLibrary(standard_store(distribution), distribution)
    rng = random.Random(16)
    for name in sorted(library.store.fielddefs):
        values = {f: random_value(library, d, rng) for f, d in library.fields(name)}
        ours = library.create(name, values).serialize()
        theirs = library.store.serialize_cdr(library.store.deserialize_cdr(ours, name), name)
        assert ours == bytes(theirs), name
        assert library.decoder(name)(ours) == values, name
        big = library.store.serialize_cdr(
            library.store.deserialize_cdr(ours, name), name, little_endian=False
        )
        assert library.decoder(name)(bytes(big)) == values, name


def rosbags_messages(library: TypeLibrary) -> dict[str, tuple[Any, dict[str, Any], Any]]:
    """The messages dura uses, each built three ways: with rosbags' classes, as dura's
    dict, and with the peer's hand-written classes."""
    t = library.store.types
    stamp = t["builtin_interfaces/msg/Time"](sec=12, nanosec=345)
    header = t["std_msgs/msg/Header"](stamp=stamp, frame_id="base_link")
    header_d = {"stamp": {"sec": 12, "nanosec": 345}, "frame_id": "base_link"}
    header_h = by_hand.Header(stamp=by_hand.Time(sec=12, nanosec=345), frame_id="base_link")
    v = t["geometry_msgs/msg/Vector3"]
    q = t["geometry_msgs/msg/Quaternion"]
    twist = t["geometry_msgs/msg/Twist"](linear=v(x=0.5, y=0.0, z=0.0), angular=v(x=0, y=0, z=0.25))
    twist_d = {"linear": {"x": 0.5, "y": 0.0, "z": 0.0}, "angular": {"x": 0.0, "y": 0.0, "z": 0.25}}
    twist_h = by_hand.Twist(linear=by_hand.Vector3(x=0.5), angular=by_hand.Vector3(z=0.25))
    cov = [float(i) / 10 for i in range(36)]
    pose = t["geometry_msgs/msg/Pose"](
        position=t["geometry_msgs/msg/Point"](x=1.0, y=2.0, z=0.0),
        orientation=q(x=0, y=0, z=0, w=1),
    )
    pose_d = {"position": {"x": 1.0, "y": 2.0, "z": 0.0},
              "orientation": {"x": 0.0, "y": 0.0, "z": 0.0, "w": 1.0}}  # fmt: skip
    pose_h = by_hand.Pose(position=by_hand.Point(x=1.0, y=2.0))
    ranges = [1.0, 2.5, 3.0]
    return {
        "sensor_msgs/msg/LaserScan": (
            t["sensor_msgs/msg/LaserScan"](
                header=header, angle_min=-1.0, angle_max=1.0, angle_increment=0.5,
                time_increment=0.0, scan_time=0.1, range_min=0.125, range_max=8.0,
                ranges=np.array(ranges, dtype=np.float32), intensities=np.array([], np.float32),
            ),
            {"header": header_d, "angle_min": -1.0, "angle_max": 1.0, "angle_increment": 0.5,
             "scan_time": 0.1, "range_min": 0.125, "range_max": 8.0, "ranges": ranges},
            by_hand.LaserScan(header=header_h, angle_min=-1.0, angle_max=1.0, angle_increment=0.5,
                              scan_time=0.1, range_min=0.125, range_max=8.0, ranges=ranges),
        ),
        "geometry_msgs/msg/Twist": (twist, twist_d, twist_h),
        "nav_msgs/msg/Odometry": (
            t["nav_msgs/msg/Odometry"](
                header=header, child_frame_id="base_footprint",
                pose=t["geometry_msgs/msg/PoseWithCovariance"](pose=pose, covariance=np.array(cov)),
                twist=t["geometry_msgs/msg/TwistWithCovariance"](
                    twist=twist, covariance=np.zeros(36)
                ),
            ),
            {"header": header_d, "child_frame_id": "base_footprint",
             "pose": {"pose": pose_d, "covariance": cov}, "twist": {"twist": twist_d}},
            by_hand.Odometry(header=header_h, child_frame_id="base_footprint",
                             pose=by_hand.PoseWithCovariance(pose=pose_h, covariance=cov),
                             twist=by_hand.TwistWithCovariance(twist=twist_h)),
        ),
        "sensor_msgs/msg/Imu": (
            t["sensor_msgs/msg/Imu"](
                header=header, orientation=q(x=0, y=0, z=0, w=1),
                orientation_covariance=np.zeros(9), angular_velocity=v(x=0, y=0, z=0.25),
                angular_velocity_covariance=np.zeros(9), linear_acceleration=v(x=0.5, y=0, z=9.75),
                linear_acceleration_covariance=np.zeros(9),
            ),
            {"header": header_d, "orientation": {"w": 1.0}, "angular_velocity": {"z": 0.25},
             "linear_acceleration": {"x": 0.5, "z": 9.75}},
            by_hand.Imu(header=header_h, angular_velocity=by_hand.Vector3(z=0.25),
                        linear_acceleration=by_hand.Vector3(x=0.5, z=9.75)),
        ),
        "diagnostic_msgs/msg/DiagnosticArray": (
            t["diagnostic_msgs/msg/DiagnosticArray"](
                header=header,
                status=[t["diagnostic_msgs/msg/DiagnosticStatus"](
                    level=2, name="dura: frequency scan", message="stopped", hardware_id="lidar/0",
                    values=[t["diagnostic_msgs/msg/KeyValue"](key="frequency", value="0")],
                )],
            ),
            {"header": header_d, "status": [{"level": 2, "name": "dura: frequency scan",
             "message": "stopped", "hardware_id": "lidar/0",
             "values": [{"key": "frequency", "value": "0"}]}]},
            by_hand.DiagnosticArray(header=header_h, status=[by_hand.DiagnosticStatus(
                level=2, name="dura: frequency scan", message="stopped", hardware_id="lidar/0",
                values=[by_hand.KeyValue(key="frequency", value="0")])]),
        ),
        "std_msgs/msg/String": (
            t["std_msgs/msg/String"](data='{"kind": "GOAL_ADDED"}'),
            {"data": '{"kind": "GOAL_ADDED"}'},
            by_hand.String(data='{"kind": "GOAL_ADDED"}'),
        ),
        "rmw_dds_common/msg/ParticipantEntitiesInfo": (
            t["rmw_dds_common/msg/ParticipantEntitiesInfo"](
                gid=t["rmw_dds_common/msg/Gid"](data=np.arange(16, dtype=np.uint8)),
                node_entities_info_seq=[t["rmw_dds_common/msg/NodeEntitiesInfo"](
                    node_namespace="/", node_name="lidar", reader_gid_seq=[],
                    writer_gid_seq=[t["rmw_dds_common/msg/Gid"](data=np.full(16, 7, np.uint8))],
                )],
            ),
            {"gid": {"data": list(range(16))}, "node_entities_info_seq": [{
             "node_namespace": "/", "node_name": "lidar", "writer_gid_seq": [{"data": [7] * 16}]}]},
            by_hand.ParticipantEntitiesInfo(
                gid=by_hand.Gid(data=list(range(16))),
                node_entities_info_seq=[by_hand.NodeEntitiesInfo(
                    node_name="lidar", writer_gid_seq=[by_hand.Gid(data=[7] * 16)])],
            ),
        ),
    }  # fmt: skip


def test_the_messages_dura_uses_are_byte_identical_to_rosbags_and_to_hand_written_types(
    jazzy: TypeLibrary,
) -> None:
    for name, (reference, values, hand) in rosbags_messages(jazzy).items():
        expected = bytes(jazzy.store.serialize_cdr(reference, name))
        assert jazzy.create(name, values).serialize() == expected, name
        assert hand.serialize() == expected, name
        assert jazzy.idl(name).__idl_typename__ == hand.__idl_typename__, name  # type: ignore[attr-defined]


def test_a_robots_own_messages_serialise_as_rosbags_does(tmp_path: Path) -> None:
    folder = tmp_path / "dock_msgs"
    (folder / "msg").mkdir(parents=True)
    (folder / "action").mkdir()
    (folder / "msg" / "Station.msg").write_text(
        "# a docking station\nuint8 FREE=0\nstring<=16 name\ngeometry_msgs/Point where\n"
        "float32[3] size\nbool[<=2] flags\nchar c\nbyte b\n"
    )
    (folder / "action" / "Dock.action").write_text(
        "Station station\n---\nbool docked\n---\nfloat64 left\n"
    )
    library = TypeLibrary(message_store("jazzy", [tmp_path]), "jazzy")
    values = {"name": "south", "where": {"x": 1.0, "y": 2.0, "z": 0.0}, "size": [1.0, 2.0, 0.5],
              "flags": [True], "c": 65, "b": 255}  # fmt: skip
    station = library.create("dock_msgs/msg/Station", values)
    assert station.__idl_typename__ == "dock_msgs::msg::dds_::Station_"  # type: ignore[attr-defined]
    data = station.serialize()
    store = library.store
    reference = store.deserialize_cdr(data, "dock_msgs/msg/Station")
    assert bytes(store.serialize_cdr(reference, "dock_msgs/msg/Station")) == data
    assert library.decoder("dock_msgs/Station")(data) == values
    goal = library.create(
        "dock_msgs/action/Dock_SendGoal_Request",
        {"goal_id": {"uuid": list(range(16))}, "goal": {"station": values}},
    )
    typename = "dock_msgs::action::dds_::Dock_SendGoal_Request_"
    assert goal.__idl_typename__ == typename  # type: ignore[attr-defined]
    name = "dock_msgs/action/Dock_SendGoal_Request"
    assert bytes(store.serialize_cdr(store.deserialize_cdr(goal.serialize(), name), name)) == (
        goal.serialize()
    )


@pytest.mark.parametrize(
    ("damage", "reason"),
    [
        (lambda b: b[:2], "not plain CDR"),
        (lambda b: b"\x00\x06" + b[2:], "not plain CDR"),  # XCDR2: not what ROS 2 sends
        (lambda b: b[:20], "not a sensor_msgs/msg/LaserScan"),
        (lambda b: b[:12] + b"\xff\xff\xff\x7f" + b[16:], "runs past the end"),
        (lambda b: b.replace(b"laser\x00", b"\xffaser\x00"), "utf-8"),
    ],
)
def test_malformed_bytes_are_a_cdr_error_naming_the_problem(
    jazzy: TypeLibrary, damage: Callable[[bytes], bytes], reason: str
) -> None:
    good = by_hand.LaserScan(header=by_hand.Header(frame_id="laser"), ranges=[1.0]).serialize()
    assert jazzy.decoder("sensor_msgs/msg/LaserScan")(good)["ranges"] == [1.0]
    with pytest.raises(CdrError, match=reason):
        jazzy.decoder("sensor_msgs/msg/LaserScan")(damage(good))


def test_exact_decoding_refuses_bytes_left_over(jazzy: TypeLibrary) -> None:
    data = by_hand.String(data="abc").serialize()
    assert jazzy.decoder("std_msgs/msg/String").exact(data + b"\x00\x00") == {"data": "abc"}
    with pytest.raises(CdrError, match="left over"):
        jazzy.decoder("std_msgs/msg/String").exact(data + bytes(8))


def test_discovery_info_of_humble_is_understood_by_a_jazzy_dura_and_the_reverse() -> None:
    humble, jazzy = (TypeLibrary(standard_store(d), d) for d in ("humble", "jazzy"))
    name = "rmw_dds_common/msg/ParticipantEntitiesInfo"
    guid, writer = bytes(range(16)), bytes([9] * 16)
    for sender, receiver, size in ((humble, jazzy, 24), (jazzy, humble, 16)):
        pad = [0] * (size - 16)
        data = sender.create(name, {
            "gid": {"data": [*guid, *pad]},
            "node_entities_info_seq": [{"node_namespace": "/robot1", "node_name": "lidar",
                                        "writer_gid_seq": [{"data": [*writer, *pad]}]}],
        }).serialize()  # fmt: skip
        found = read_entities_info(data, gid_layouts(receiver))
        assert found == (size, guid, [("/robot1/lidar", [], [writer])])


def test_an_unknown_type_or_field_is_a_config_error(jazzy: TypeLibrary) -> None:
    with pytest.raises(ConfigError, match="did you mean 'sensor_msgs/msg/LaserScan'"):
        jazzy.idl("sensor_msgs/msg/LaserScn")
    with pytest.raises(ConfigError, match="has no field 'rangez'"):
        jazzy.create("sensor_msgs/msg/LaserScan", {"rangez": []})
    assert jazzy.of_dds("sensor_msgs::msg::dds_::LaserScan_") == "sensor_msgs/msg/LaserScan"
    assert jazzy.of_dds("custom_msgs::msg::dds_::Thing_") is None
