"""ROS 2 bags written with ``rosbags`` for the tests: a lidar that stops, a topic of a
type nobody knows, a bag cut short, scans that do not decode; and dura recordings."""

from __future__ import annotations

import contextlib
import sqlite3
from collections.abc import Mapping
from pathlib import Path

import numpy as np
import yaml
from mcap.writer import Writer as McapWriter
from rosbags.rosbag2 import CompressionFormat, CompressionMode, StoragePlugin, Writer
from rosbags.typesys import Stores, get_types_from_msg, get_typestore

from executive.bags.recording import Recorder
from executive.bus.message import Message
from executive.testing.harness import robot_variant
from tests.conftest import USECASE

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
    compression: str = "",
    broken: Mapping[int, bytes] | None = None,
) -> Path:
    """A rosbag2 folder with a lidar's scan at 10 Hz that stops for 2 s at 10 s
    (``compression``: rosbag2's zstd per ``file`` or per ``message``; ``broken``: the
    bytes of the k-th message instead of its scan)."""
    writer = Writer(path, version=version, storage_plugin=STORAGES[storage])  # type: ignore[arg-type]
    if compression:
        mode = {"file": CompressionMode.FILE, "message": CompressionMode.MESSAGE}
        writer.set_compression(mode[compression], CompressionFormat.ZSTD)
    with writer:
        connection = writer.add_connection(topic, SCAN, typestore=TYPES)
        for k, t in enumerate(scan_times() if times is None else times):
            writer.write(connection, t, (broken or {}).get(k) or scan(t))
    return path


UNKNOWN = "acme_msgs/msg/Sweep"
SWEEP = "float32 angle\n"


def write_unknown_type_bag(path: Path, times: list[int] | None = None) -> Path:
    """A sqlite3 bag of a type nobody knows, without its definition (as Humble wrote
    them): ten messages at 10 Hz, or one at each of ``times``."""
    types = get_typestore(Stores.EMPTY)
    types.register(get_types_from_msg(SWEEP, UNKNOWN))
    with Writer(path, version=8, storage_plugin=StoragePlugin.SQLITE3) as writer:
        connection = writer.add_connection("/scan", UNKNOWN, typestore=types)
        for k, t in enumerate(times or [T0 * 10**9 + k * 10**8 for k in range(10)]):
            message = types.types[UNKNOWN](angle=float(k))
            data = bytes(types.serialize_cdr(message, UNKNOWN))
            writer.write(connection, t, data)
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


# The sqlite3 schema and metadata.yaml version each ROS 2 distribution's rosbag2 wrote.
SQLITE3_SCHEMAS = {
    "eloquent": (1, 3),  # topics without QoS, no schema table
    "foxy": (2, 4),  # topics with QoS profiles
    "humble": (3, 5),  # a schema table, a metadata table
    "jazzy": (4, 9),  # message definitions, type hashes (as rosbags writes it)
}
QOS = (  # as Foxy wrote it in metadata.yaml: its database says 2147483647 for "none"
    "- history: 3\n  depth: 0\n  reliability: 1\n  durability: 2\n  deadline:\n    sec: 0\n"
    "    nsec: 0\n  lifespan:\n    sec: 0\n    nsec: 0\n  liveliness: 1\n"
    "  liveliness_lease_duration:\n    sec: 0\n    nsec: 0\n"
    "  avoid_ros_namespace_conventions: false"
)
_TOPICS = {
    1: "id INTEGER PRIMARY KEY, name TEXT NOT NULL, type TEXT NOT NULL, "
    "serialization_format TEXT NOT NULL",
    2: "id INTEGER PRIMARY KEY, name TEXT NOT NULL, type TEXT NOT NULL, "
    "serialization_format TEXT NOT NULL, offered_qos_profiles TEXT NOT NULL",
}
_COLUMNS = {1: "id, name, type, serialization_format", 2: _TOPICS[2].replace(
    " INTEGER PRIMARY KEY", "").replace(" TEXT NOT NULL", "")}  # fmt: skip


def as_written_by(folder: Path, distribution: str) -> Path:
    """Rewrite a rosbags sqlite3 bag as ``distribution``'s rosbag2 wrote it: its tables'
    schema, its metadata version, and a ``metadata.yaml`` whose topics come in another
    order with QoS text that differs from the database's, as in rosbag2's test bags."""
    schema, version = SQLITE3_SCHEMAS[distribution]
    with contextlib.closing(sqlite3.connect(next(folder.glob("*.db3")))) as db, db:
        if schema < 4:
            db.execute("DROP TABLE message_definitions")
            columns = _TOPICS[min(schema, 2)]
            db.execute(f"CREATE TABLE topics_old({columns})")
            names = _COLUMNS[min(schema, 2)]
            db.execute(f"INSERT INTO topics_old SELECT {names} FROM topics")  # noqa: S608 - ours
            db.execute("DROP TABLE topics")
            db.execute("ALTER TABLE topics_old RENAME TO topics")
        if schema == 3:
            db.execute("UPDATE schema SET schema_version = 3, ros_distro = 'humble'")
        if schema < 3:
            db.execute("DROP TABLE schema")
            db.execute("DROP TABLE metadata")
    metadata = folder / "metadata.yaml"
    info = yaml.safe_load(metadata.read_text())
    bag = info["rosbag2_bagfile_information"]
    bag["version"] = version
    for key in ("custom_data", "files", "ros_distro") if version < 9 else ():
        bag.pop(key, None)
    bag["topics_with_message_count"].reverse()
    bag["topics_with_message_count"].append(
        {"message_count": 0, "topic_metadata": {"name": "/parameter_events",
         "type": "rcl_interfaces/msg/ParameterEvent", "serialization_format": "cdr"}}
    )  # fmt: skip
    for topic in bag["topics_with_message_count"]:
        topic["topic_metadata"]["offered_qos_profiles"] = QOS
        topic["topic_metadata"].pop("type_description_hash", None)
    metadata.write_text(yaml.safe_dump(info))
    return folder


def write_split_bag(
    path: Path, storage: str, parts: list[list[int]], *, compression: str = ""
) -> Path:
    """A scan bag in several files, ``parts`` the receive times in each (as rosbag2
    splits a bag by size or duration)."""
    path.mkdir()
    files, infos = [], []
    for index, times in enumerate(parts):
        part = write_scan_bag(path.parent / f"{path.name}_part{index}", storage, times=times,
                              compression=compression)  # fmt: skip
        info = yaml.safe_load((part / "metadata.yaml").read_text())["rosbag2_bagfile_information"]
        (source,) = [part / name for name in info["relative_file_paths"]]
        target = path / source.name.replace(part.name, f"{path.name}_{index}")
        source.rename(target)
        files.append(target.name)
        infos.append(info)
    merged = dict(infos[0])
    merged["relative_file_paths"] = files
    merged["message_count"] = sum(i["message_count"] for i in infos)
    merged.pop("files", None)
    (path / "metadata.yaml").write_text(yaml.safe_dump({"rosbag2_bagfile_information": merged}))
    return path


BROKEN = {  # three scans of 180 that are not LaserScans
    5: scan(scan_times()[5])[:30],  # cut short
    7: b"\x00\x01\x00\x00" + b"\xff" * 40,  # a CDR header, then a length past the end
    50: b"garbage!",  # not even CDR
}
CUT_SHORT = (
    "malformed sensor_msgs/msg/LaserScan from lidar (not a sensor_msgs/msg/LaserScan: "
    "unpack_from requires a buffer of at least 28 bytes for unpacking 4 bytes at offset 24 "
    "(actual buffer size is 26))"
)


def stamped_robot(folder: Path) -> Path:
    """The use case's robot whose lidar is watched by a timestamp observer: it decodes
    every scan (frequency and timeout observers use only their times)."""
    timestamp = {"type": "timestamp", "topics": [{"name": "scan", "filter": {"type": "mean", "window_size": 5}, "states": [
        {"state": "ok", "number": 1, "age": {"type": "less_than", "less_than": 0.5}}]}]}  # fmt: skip
    return robot_variant(
        USECASE, folder, {"functionalities": {"lidar": {"observers": [timestamp]}}}
    )


def record(path: Path, rows: list[tuple[str, bytes, str, float]]) -> Path:
    """A dura recording of ``(key, raw payload, caller, seconds after T0)`` messages."""
    with Recorder(path, "usecase") as recorder:
        for key, raw, caller, t in rows:
            recorder.write(
                Message.at_ns(key, raw, caller, None, T0 * 10**9 + round(t * 10) * 10**8)
            )
    return path
