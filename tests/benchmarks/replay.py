"""Benchmark of ``dura replay``: messages per second through the observers, beside
reading the bag alone, measured in the same run.

    python -m tests.benchmarks.replay [--seconds S] [--repeat N]

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
"""

from __future__ import annotations

import argparse
import tempfile
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
from rosbags.rosbag2 import StoragePlugin, Writer

from executive.bags.bag import routes
from executive.bags.reader import open_bag
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


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=120.0, help="length of the bag (s)")
    parser.add_argument("--repeat", type=int, default=3, help="runs per figure (the best counts)")
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


if __name__ == "__main__":
    main()
