"""Benchmark of ``dura replay``: messages per second through the observers, beside
reading the bag alone, measured in the same run.

    python -m tests.benchmarks.replay [--seconds S] [--repeat N] [--runs N] [--messages N]

It writes a ROS 2 bag with ``rosbags`` (MCAP and sqlite3): a lidar's LaserScan (360
ranges) at 40 Hz, odometry at 50 Hz and an IMU at 100 Hz for S seconds. For each
storage the table shows how fast the bag is read alone (bus messages made, nothing
decoded), read and decoded (every message to a dict), and replayed through the
use-case robot's monitoring (observers, diagnosis, repair rules) with frequency and
timeout observers on the three topics (which never decode), and with timestamp
observers as well (which decode every message), in messages per second and as a
multiple of real time; OPEN is the time to open the bag and set up the robot's
monitoring (reading the description, its observers, rules and message types), which
the replay figures leave out. Each figure is the best of N runs.

Then two tables measured in the same run. Start-up: the time from starting ``dura
replay`` of a small bag (5 s, both storages) to its first line of output, beside
reading and decoding the same bag with ``rosbags`` alone in a fresh process (median of
N interleaved runs; the goal: under 1 s and at most twice rosbags). Recording: the
messages per second and the CPU per message of dura's recorder (``dura record``, ``dura
run --record``: a JSON scan payload per message, a whole chunk on disk every second),
beside a plain MCAP writer writing the same bytes with the same one-second flush.
"""

from __future__ import annotations

import argparse
import json
import statistics
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
from mcap.writer import CompressionType
from mcap.writer import Writer as McapWriter
from rosbags.rosbag2 import StoragePlugin, Writer

from executive.bags.bag import routes
from executive.bags.reader import open_bag
from executive.bags.recording import Recorder
from executive.bus.keys import topic
from executive.bus.message import Message
from executive.testing.harness import robot_variant
from executive.testing.replay import BagReplay
from knowledge.robot import load_robot
from monitoring.replay import watched_topics
from tests.conftest import USECASE
from tests.executive.bags.recorded import SCAN, T0, TYPES, scan

RATES = {"/scan": 40, "/odom": 50, "/imu": 100}  # Hz
TYPE = {"/scan": SCAN, "/odom": "nav_msgs/msg/Odometry", "/imu": "sensor_msgs/msg/Imu"}


def _header(t_ns: int) -> Any:
    time_type = TYPES.types["builtin_interfaces/msg/Time"]
    stamp = time_type(sec=t_ns // 10**9, nanosec=t_ns % 10**9)
    return TYPES.types["std_msgs/msg/Header"](stamp=stamp, frame_id="base")


def _odometry(t_ns: int) -> bytes:
    t = TYPES.types
    vector = t["geometry_msgs/msg/Vector3"](x=0.5, y=0.0, z=0.0)
    twist = t["geometry_msgs/msg/Twist"](linear=vector, angular=vector)
    pose = t["geometry_msgs/msg/Pose"](
        position=t["geometry_msgs/msg/Point"](x=1.0, y=2.0, z=0.0),
        orientation=t["geometry_msgs/msg/Quaternion"](x=0.0, y=0.0, z=0.0, w=1.0),
    )
    covariance = np.zeros(36, dtype=np.float64)
    message = t["nav_msgs/msg/Odometry"](
        header=_header(t_ns),
        child_frame_id="base_link",
        pose=t["geometry_msgs/msg/PoseWithCovariance"](pose=pose, covariance=covariance),
        twist=t["geometry_msgs/msg/TwistWithCovariance"](twist=twist, covariance=covariance),
    )
    return bytes(TYPES.serialize_cdr(message, "nav_msgs/msg/Odometry"))


def _imu(t_ns: int) -> bytes:
    t = TYPES.types
    vector = t["geometry_msgs/msg/Vector3"](x=0.0, y=0.0, z=9.81)
    message = t["sensor_msgs/msg/Imu"](
        header=_header(t_ns),
        orientation=t["geometry_msgs/msg/Quaternion"](x=0.0, y=0.0, z=0.0, w=1.0),
        orientation_covariance=np.zeros(9, dtype=np.float64),
        angular_velocity=vector,
        angular_velocity_covariance=np.zeros(9, dtype=np.float64),
        linear_acceleration=vector,
        linear_acceleration_covariance=np.zeros(9, dtype=np.float64),
    )
    return bytes(TYPES.serialize_cdr(message, "sensor_msgs/msg/Imu"))


MAKE: dict[str, Callable[[int], bytes]] = {"/scan": scan, "/odom": _odometry, "/imu": _imu}


def write_bag(path: Path, storage: StoragePlugin, seconds: float) -> int:
    """The benchmark's bag; how many messages it holds."""
    times = sorted(
        (T0 * 10**9 + round(k * 1e9 / rate), name)
        for name, rate in RATES.items()
        for k in range(round(seconds * rate))
    )
    with Writer(path, version=9, storage_plugin=storage) as writer:
        connections = {n: writer.add_connection(n, TYPE[n], typestore=TYPES) for n in RATES}
        for t, name in times:
            writer.write(connections[name], t, MAKE[name](t))
    return len(times)


def observers(kinds: tuple[str, ...]) -> list[dict[str, Any]]:
    """Observers of the given kinds on every topic of the bag."""
    out: list[dict[str, Any]] = []
    for name, rate in RATES.items():
        topic = name.strip("/")
        ok = {"state": "ok", "number": 1}
        if "frequency" in kinds:
            bounds = {"type": "in_between", "lower_bound": 0.8 * rate, "upper_bound": 1.2 * rate}
            out.append({"type": "frequency", "main_loop_rate": 2.0, "topics": [
                {"name": topic, "filter": {"type": "mean", "window_size": 50},
                 "states": [{**ok, "frequency": bounds}]}]})  # fmt: skip
            out.append({"type": "timeout", "topics": [{"name": topic, "timeout": 0.5}]})
        if "timestamp" in kinds:
            out.append({"type": "timestamp", "topics": [
                {"name": topic, "filter": {"type": "median", "window_size": 20},
                 "states": [{**ok, "age": {"type": "less_than", "less_than": 0.5}}]}]})  # fmt: skip
    return out


def best(repeat: int, run: Callable[[], object]) -> float:
    """The shortest of ``repeat`` runs, in seconds."""
    times = []
    for _ in range(repeat):
        began = time.perf_counter()
        run()
        times.append(time.perf_counter() - began)
    return min(times)


def best_replay(repeat: int, path: Path, robot: Path, count: int) -> tuple[float, float]:
    """The shortest set-up and replay of ``repeat`` runs, in seconds."""
    opened, replayed = [], []
    for _ in range(repeat):
        began = time.perf_counter()
        with BagReplay(path, robot) as session:
            ready = time.perf_counter()
            timeline = session.run()
            replayed.append(time.perf_counter() - ready)
        opened.append(ready - began)
        assert timeline.messages == count
    return min(opened), min(replayed)


ROSBAGS_READ = """
import sys
from pathlib import Path
from rosbags.highlevel import AnyReader
from rosbags.typesys import Stores, get_typestore
with AnyReader([Path(sys.argv[1])], default_typestore=get_typestore(Stores.LATEST)) as reader:
    count = sum(1 for c, _, raw in reader.messages() if reader.deserialize(raw, c.msgtype))
print(count)
"""


def first_line(argv: list[str]) -> float:
    """Seconds from starting a command to its first line of output."""
    began = time.perf_counter()
    with subprocess.Popen(argv, stdout=subprocess.PIPE, stderr=subprocess.STDOUT) as process:
        assert process.stdout is not None
        process.stdout.readline()
        took = time.perf_counter() - began
        process.communicate()
    return took


def start_up(root: Path, runs: int) -> None:
    """Time to first output of ``dura replay`` beside ``rosbags`` in a fresh process."""
    dura = str(Path(sys.executable).parent / "dura")
    print(f"\nstart-up, a 5 s bag (median of {runs} interleaved runs; goal < 1 s and <= 2x):")
    print(f"{'STORAGE':<8} {'DURA REPLAY s':>13}  {'ROSBAGS s':>9}  {'RATIO':>5}")
    for storage in (StoragePlugin.MCAP, StoragePlugin.SQLITE3):
        path = root / f"small_{storage.name.lower()}"
        write_bag(path, storage, 5.0)
        ours, theirs = [], []
        for _ in range(runs):
            ours.append(first_line([dura, "replay", str(path), "--robot", str(USECASE)]))
            theirs.append(first_line([sys.executable, "-c", ROSBAGS_READ, str(path)]))
        a, b = statistics.median(ours), statistics.median(theirs)
        print(f"{storage.name.lower():<8} {a:>13.3f}  {b:>9.3f}  {a / b:>5.2f}")


def recording(root: Path, count: int, repeat: int) -> None:
    """Messages per second and CPU per message: dura's recorder beside a plain writer."""
    payloads = [
        json.dumps({"stamp": T0 + k / 40, "ranges": [2.0] * 360}).encode() for k in range(count)
    ]
    messages = [
        Message(topic("scan"), raw, "lidar", T0 + k / 40, T0 + k / 40)
        for k, raw in enumerate(payloads)
    ]

    def ours() -> None:
        with Recorder(root / "dura.mcap", "usecase", max_size=1 << 40, keep=0) as recorder:
            for message in messages:
                recorder.write(message)

    def plain() -> None:
        with (root / "plain.mcap").open("wb") as stream:
            writer = McapWriter(stream, compression=CompressionType.ZSTD)
            writer.start()
            schema = writer.register_schema("dura.TopicMessage", "jsonschema", b"{}")
            channel = writer.register_channel("topic/scan", "json", schema, {"caller_id": "lidar"})
            flushed = time.monotonic()
            for k, raw in enumerate(payloads):
                t = round((T0 + k / 40) * 1e9)
                writer.add_message(channel, t, raw, t, k)
                if time.monotonic() - flushed >= 1.0:
                    writer.flush()  # type: ignore[no-untyped-call]
                    flushed = time.monotonic()
            writer.finish()  # type: ignore[no-untyped-call]

    print(f"\nrecording {count} scan messages (JSON, 360 ranges), a whole chunk every second:")
    print(f"{'WRITER':<20} {'MSG/S':>9}  {'CPU us/MSG':>10}")
    for label, run in (("dura's recorder", ours), ("plain MCAP writer", plain)):
        walls, cpus = [], []
        for _ in range(repeat):
            wall, cpu = time.perf_counter(), time.process_time()
            run()
            walls.append(time.perf_counter() - wall)
            cpus.append(time.process_time() - cpu)
        print(f"{label:<20} {count / min(walls):>9.0f}  {1e6 * min(cpus) / count:>10.1f}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=120.0, help="length of the bag (s)")
    parser.add_argument("--repeat", type=int, default=3, help="runs per figure (the best counts)")
    parser.add_argument("--runs", type=int, default=7, help="runs of each start-up (the median)")
    parser.add_argument("--messages", type=int, default=100000, help="messages recorded")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as folder:
        root = Path(folder)
        robots = {
            label: robot_variant(
                USECASE, root / label, {"functionalities": {"robot_base": {"observers": observers(kinds)}, "lidar": {"observers": []}}}
            )
            for label, kinds in (("freq+timeout", ("frequency",)), ("+timestamp", ("frequency", "timestamp")))
        }  # fmt: skip
        print(
            f"bag: {args.seconds:g} s of LaserScan at {RATES['/scan']} Hz, odometry at "
            f"{RATES['/odom']} Hz, IMU at {RATES['/imu']} Hz; best of {args.repeat} runs"
        )
        print(
            f"{'STORAGE':<8} {'MESSAGES':>8}  {'READ':>9}  {'READ+DECODE':>11}  "
            f"{'REPLAY FREQ+TIMEOUT':>24}  {'REPLAY +TIMESTAMP':>24}  {'OPEN s':>6}"
        )
        for storage in (StoragePlugin.MCAP, StoragePlugin.SQLITE3):
            path = root / f"bag_{storage.name.lower()}"
            count = write_bag(path, storage, args.seconds)
            robot = load_robot(robots["freq+timeout"])

            def read(decode: bool, path: Path = path, robot: Any = robot) -> None:
                with open_bag(path) as bag:
                    found = routes(bag, robot, watched=watched_topics(robot))
                    for message in bag.messages(found):
                        if decode:
                            message.payload  # noqa: B018 - decoding is what is measured

            opened, plain = best_replay(args.repeat, path, robots["freq+timeout"], count)
            _, decoding = best_replay(args.repeat, path, robots["+timestamp"], count)
            rates = [
                count / best(args.repeat, lambda: read(False)),
                count / best(args.repeat, lambda: read(True)),
                count / plain,
                count / decoding,
            ]
            realtime = [r * args.seconds / count for r in rates]
            print(
                f"{storage.name.lower():<8} {count:>8}  {rates[0]:>9.0f}  {rates[1]:>11.0f}  "
                f"{rates[2]:>11.0f} ({realtime[2]:>5.0f}x rt)  "
                f"{rates[3]:>11.0f} ({realtime[3]:>5.0f}x rt)  {opened:>5.2f}"
            )
        print("(msg/s; 'x rt': seconds of bag replayed per second)")
        start_up(root, args.runs)
        recording(root, args.messages, args.repeat)


if __name__ == "__main__":
    main()
