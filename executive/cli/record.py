"""``dura record [--robot ROBOT.yaml] OUT.mcap``: record a running robot's bus traffic
and ROS 2 topics; ``dura record --repair FILE``: make a recording cut off by a crash
whole again."""

from __future__ import annotations

import argparse
import contextlib
import sys
import threading
from pathlib import Path
from typing import Any

from executive.bags.recording import (
    DEFAULT_FLUSH_EVERY,
    DEFAULT_KEEP,
    DEFAULT_MAX_SIZE,
    MB,
    BusRecording,
    repair,
)
from executive.bus.api.components import COMPONENT_LIST, lifecycle
from executive.bus.keys import EXECUTIVE_ALIVE
from executive.bus.wording import plural
from executive.cli.arguments import count, megabytes, seconds
from executive.cli.client import add_client_options, connect, described_robot
from executive.cli.output import add_json_flag, print_json, shown
from executive.cli.stopping import stop_on_signals, wait
from knowledge.errors import BagError


def register(sub: Any) -> None:
    p = sub.add_parser(
        "record",
        help="record a running robot's bus traffic to MCAP",
        description="Record what a running robot says on its bus (component topics, "
        "observations, diagnoses, resources, events and component states) to an MCAP file "
        "with JSON schemas, for MCAP tools and 'dura replay'; and a ROS 2 robot's ROS 2 "
        "topics as rosbag2 does (CDR, ros2msg schemas), from a ROS 2 node of its own "
        "(dura_record). It stops on Ctrl-C or "
        "SIGTERM, or when the executive stops. The file is rotated at --max-size "
        "(OUT.mcap becomes OUT.1.mcap, ...), with --keep older files kept. What was "
        "recorded is on disk as a whole chunk every --flush seconds, so a recorder "
        "killed loses at most that; 'dura record --repair FILE' makes such a file whole.",
    )
    p.add_argument("out", metavar="OUT.mcap", type=Path, nargs="?", help="the recording")
    p.add_argument(
        "--repair", metavar="FILE", type=Path,
        help="rewrite a recording cut off by a crash as a whole file, with its messages up "
        "to its last whole chunk, and say how much was cut (no robot needed)",
    )  # fmt: skip
    p.add_argument(
        "--ros2-bag", metavar="FILE", type=Path,
        help="write the ROS 2 topics of recording FILE as a rosbag2 bag (for rosbags, "
        "'ros2 bag' and Foxglove) in the folder OUT (default: FILE's name with _ros2); "
        "dura's own messages stay in FILE (no robot needed)",
    )  # fmt: skip
    p.add_argument(
        "--flush", type=seconds(), default=DEFAULT_FLUSH_EVERY, metavar="S",
        help=f"write a whole chunk at least every S seconds (default {DEFAULT_FLUSH_EVERY:g})",
    )  # fmt: skip
    add_client_options(p)
    p.add_argument(
        "--max-size",
        type=megabytes,
        default=DEFAULT_MAX_SIZE,
        metavar="MB",
        help=f"rotate the file at this size (default {DEFAULT_MAX_SIZE // MB})",
    )
    p.add_argument(
        "--keep",
        type=count,
        default=DEFAULT_KEEP,
        metavar="N",
        help=f"older files to keep (default {DEFAULT_KEEP})",
    )
    add_json_flag(p)
    p.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    if args.repair is not None:
        return run_repair(args)
    if args.ros2_bag is not None:
        return run_ros2_bag(args)
    if args.out is None:
        raise BagError("record: give OUT.mcap to record to, or --repair FILE")
    robot = described_robot(args)
    stop = stop_on_signals()
    with contextlib.ExitStack() as stack:
        bus = stack.enter_context(connect(args))
        seen = threading.Event()

        def on_executive(_: str, alive: bool) -> None:
            if alive:
                seen.set()
            elif seen.is_set():
                stop.set()  # the executive stopped: so does its recording

        bus.watch_alive(EXECUTIVE_ALIVE, on_executive)
        states = [lifecycle(c).to_payload() for c in COMPONENT_LIST.call(bus).components]
        ros2 = None
        if robot.ros2 is not None:  # its ROS 2 topics, from a node of its own: dura_record
            from executive.ros2.link import Ros2Link  # Cyclone DDS: only for a ROS 2 robot

            ros2 = stack.enter_context(Ros2Link.of(robot, "record"))
        recording = BusRecording.to_file(
            bus,
            args.out,
            max_size=args.max_size,
            keep=args.keep,
            flush_every=args.flush,
            ros2=None if ros2 is None else ros2.topics,
            on_failure=lambda _: stop.set(),
        )
        recorder = recording.recorder
        recording.start(states)
        if not args.json:
            print(
                f"dura: recording robot '{bus.robot}' to {shown(args.out)} (rotated at "
                f"{args.max_size / MB:g} MB, {args.keep} older files kept); Ctrl-C stops it"
            )
            sys.stdout.flush()
        try:
            wait(stop)
        finally:
            recording.stop()
    if recording.failure is not None:
        raise recording.failure
    if args.json:
        print_json({"path": str(args.out), "messages": recorder.messages, "files": recorder.files})
    else:
        print(
            f"dura: recorded {plural(recorder.messages, 'message')} of robot '{bus.robot}' in "
            f"{plural(recorder.files, 'file')}, the newest {shown(args.out)}"
        )
    return 0


def run_repair(args: argparse.Namespace) -> int:
    repaired = repair(args.repair)
    if args.json:
        print_json({"path": str(args.repair), **vars(repaired)})
        return 0
    until = "" if repaired.end is None else f", the last at {repaired.end:.3f}"
    if not repaired.rewritten:
        print(f"dura: {shown(args.repair)} is whole ({plural(repaired.messages, 'message')})")
    else:
        print(
            f"dura: repaired {shown(args.repair)}: kept {plural(repaired.messages, 'message')}"
            f"{until}; cut {repaired.lost} bytes after its last whole chunk"
        )
    return 0


def run_ros2_bag(args: argparse.Namespace) -> int:
    from executive.bags.export import export_ros2  # rosbags' writer: only here

    source: Path = args.ros2_bag
    out = args.out or source.with_name(source.stem + "_ros2")
    exported = export_ros2(source, out)
    if args.json:
        print_json({"path": str(out), "topics": list(exported.topics),
                    "messages": exported.messages, "left": list(exported.left)})  # fmt: skip
        return 0
    topics = ", ".join(exported.topics) or "none"
    print(
        f"dura: wrote {plural(exported.messages, 'message')} of {shown(source)} to the ROS 2 "
        f"bag {shown(out)} (topics: {topics}); {plural(len(exported.left), 'channel')} of "
        "dura's own stay in the recording"
    )
    return 0
