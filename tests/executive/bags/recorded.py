"""ROS 2 bags written with ``rosbags`` for the tests: a lidar that stops, a topic of a
type nobody knows, a bag cut short."""

from __future__ import annotations

import contextlib
import sqlite3
from pathlib import Path

import numpy as np
from mcap.writer import Writer as McapWriter
from rosbags.rosbag2 import StoragePlugin, Writer
from rosbags.typesys import Stores, get_types_from_msg, get_typestore

T0 = 1_700_000_000  # seconds since the epoch: the bags' first message
SCAN = "sensor_msgs/msg/LaserScan"
TYPES = get_typestore(Stores.ROS2_HUMBLE)
STORAGES = {"mcap": StoragePlugin.MCAP, "sqlite3": StoragePlugin.SQLITE3}


def scan(t_ns: int) -> bytes:
    """A LaserScan stamped ``t_ns``, as CDR."""
    header = TYPES.types["std_msgs/msg/Header"](
        stamp=TYPES.types["builtin_interfaces/msg/Time"](sec=t_ns // 10**9, nanosec=t_ns % 10**9),
        frame_id="laser",
    )
    message = TYPES.types[SCAN](
        header=header, angle_min=-1.57, angle_max=1.57, angle_increment=0.01,
        time_increment=0.0, scan_time=0.1, range_min=0.1, range_max=10.0,
        ranges=np.full(360, 2.0, dtype=np.float32), intensities=np.zeros(0, dtype=np.float32),
    )  # fmt: skip
    return bytes(TYPES.serialize_cdr(message, SCAN))


def scan_times(stops: tuple[float, float] | None = (10.0, 12.0), length: float = 20.0) -> list[int]:
    """Receive times (ns) of a 10 Hz scan that is silent from ``stops[0]`` to ``stops[1]``."""
    times = []
    for k in range(round(length * 10)):
        t = k / 10
        if stops is None or not stops[0] <= t < stops[1]:
            times.append(T0 * 10**9 + k * 10**8)
    return times


def write_scan_bag(
    path: Path,
    storage: str = "mcap",
    *,
    topic: str = "/scan",
    times: list[int] | None = None,
    version: int = 9,
) -> Path:
    """A rosbag2 folder with a lidar's scan at 10 Hz that stops for 2 s at 10 s."""
    with Writer(path, version=version, storage_plugin=STORAGES[storage]) as writer:  # type: ignore[arg-type]
        connection = writer.add_connection(topic, SCAN, typestore=TYPES)
        for t in scan_times() if times is None else times:
            writer.write(connection, t, scan(t))
    return path


UNKNOWN = "acme_msgs/msg/Sweep"
SWEEP = "float32 angle\n"


def write_unknown_type_bag(path: Path) -> Path:
    """A sqlite3 bag of a type nobody knows, without its definition (as Humble wrote them)."""
    types = get_typestore(Stores.EMPTY)
    types.register(get_types_from_msg(SWEEP, UNKNOWN))
    with Writer(path, version=8, storage_plugin=StoragePlugin.SQLITE3) as writer:
        connection = writer.add_connection("/scan", UNKNOWN, typestore=types)
        for k in range(10):
            message = types.types[UNKNOWN](angle=float(k))
            data = bytes(types.serialize_cdr(message, UNKNOWN))
            writer.write(connection, T0 * 10**9 + k * 10**8, data)
    (database,) = path.glob("*.db3")
    with contextlib.closing(sqlite3.connect(database)) as db, db:
        db.execute("DELETE FROM message_definitions")
    return path


def write_mcap(
    path: Path,
    records: list[tuple[int, int]],
    *,
    topic: str = "/scan",
    metadata: dict[str, str] | None = None,
    schema: bool = True,
) -> Path:
    """A rosbag2-profile MCAP file of scans, each record (receive ns, publish ns), as
    ROS 2 Jazzy records them; ``metadata`` goes on the channel."""
    text, _ = TYPES.generate_msgdef(SCAN, ros_version=2)
    with path.open("wb") as stream:
        writer = McapWriter(stream)
        writer.start(profile="ros2", library="tests")
        schema_id = writer.register_schema(SCAN, "ros2msg", text.encode()) if schema else 0
        channel = writer.register_channel(topic, "cdr", schema_id, metadata or {})
        for received, published in records:
            writer.add_message(channel, received, scan(published), published)
        writer.finish()
    return path
