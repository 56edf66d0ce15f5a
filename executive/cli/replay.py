"""``dura replay BAG --robot ROBOT.yaml``: a recording through the robot's observers,
diagnosis and repair rules, with the recording's time as the clock."""

from __future__ import annotations

import argparse
import sys
import time
from collections.abc import Iterable, Iterator
from pathlib import Path
from typing import Any, TextIO

from executive.bag_replay import BagReplay, MessageCounts
from executive.bus.message import Message
from executive.bus.wording import plural
from executive.cli.arguments import factor, seconds
from executive.cli.output import add_json_flag, print_json, shown
from knowledge.robot import load_robot
from monitoring.replay import Replay
from monitoring.timeline import Entry, RepairEntry, Timeline

PROGRESS_AFTER = 1.0  # seconds of replay before progress shows (on a terminal only)
PROGRESS_EVERY = 0.25  # seconds between two progress lines


def register(sub: Any) -> None:
    p = sub.add_parser(
        "replay",
        help="replay a recording through the robot's observers, diagnosis and rules",
        description="Replay a ROS 2 bag (rosbag2: MCAP or sqlite3) or a recording of a dura "
        "run ('dura record') through the robot's observers, the diagnosis engine and the "
        "repair rules, with the recording's time as the clock, as fast as possible or at "
        "--rate. Repair actions are reported, never run. Prints a timeline of the "
        "observations that changed, the diagnoses and the would-be repairs, then how long "
        "each diagnosis held. Recorded topics go to the robot's topics of the same name "
        "(without the leading slash) or as --map says. Messages that do not decode are "
        "counted per topic and reported in the summary; the replay goes on without them. "
        "Exit 1 on a bad recording or a missing mapping.",
    )
    p.add_argument("bag", metavar="BAG", type=Path, help="a rosbag2 folder, .mcap or .db3 file")
    p.add_argument(
        "--robot", metavar="ROBOT.yaml", type=Path, required=True, help="the robot description"
    )
    p.add_argument(
        "--rate",
        type=factor,
        metavar="R",
        help="play at R times the recorded speed (default: at once)",
    )
    p.add_argument(
        "--from", dest="begin", type=seconds(zero=True), metavar="S",
        help="start S seconds after the recording's start",
    )  # fmt: skip
    p.add_argument(
        "--to", dest="end", type=seconds(zero=True), metavar="S",
        help="end S seconds after the recording's start",
    )  # fmt: skip
    p.add_argument(
        "--map", action="append", default=[], metavar="BAG_TOPIC=TOPIC",
        help="replay a recorded topic as one of the robot's (repeatable)",
    )  # fmt: skip
    p.add_argument(
        "--types", action="append", default=[], type=Path, metavar="DIR",
        help="read message types the bag does not define from the .msg, .srv, .action "
        "(laid out as in ROS packages) and .idl files under DIR (repeatable)",
    )  # fmt: skip
    add_json_flag(p)
    p.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    robot = load_robot(args.robot, domain=False)  # a replay plans nothing
    printer = None if args.json else Printer(sys.stdout)
    with BagReplay(
        args.bag,
        robot,
        maps=args.map,
        begin=args.begin,
        end=args.end,
        on_entry=printer.entry if printer is not None else None,
        types=args.types,
    ) as session:
        bag = session.bag
        if printer is not None:
            printer.header(session)
        messages: Iterable[Message] = session.messages()
        if args.rate:
            messages = paced(messages, session.replay, session.start_ns, args.rate)
        if printer is not None and sys.stderr.isatty():
            messages = Progress(sys.stderr, session.start, session.end).wrap(messages)
        timeline = session.run(messages)
        counts = session.counts(timeline)
        tolerance = session.replay.loop
    if printer is not None:
        printer.tolerance = tolerance
        printer.summary(timeline, counts, bag.notes)
    else:
        print_json(
            {
                "bag": str(args.bag),
                "format": bag.format,
                "robot": robot.name,
                "routes": {name: vars(route) for name, route in session.routes.items()},
                **timeline.to_payload(),
                "counts": counts.to_payload(),
                "notes": bag.notes,
                "live": {"tolerance": tolerance, "differences": timeline.differences(tolerance)},
            }
        )
    return 0


def paced(
    messages: Iterable[Message], replay: Replay, start_ns: int, rate: float
) -> Iterator[Message]:
    """Yield each message at its time at ``rate`` times the recorded speed, running what
    is due between them at its own time."""
    began = time.monotonic()
    for message in messages:
        while True:
            due = began + (message.received_ns - start_ns) / 1e9 / rate
            now = time.monotonic()
            if now >= due:
                break
            time.sleep(min(0.05, due - now))
            replay.advance(start_ns + round((time.monotonic() - began) * rate * 1e9))
        yield message


class Progress:
    """How far a long replay is, on one line of a terminal."""

    def __init__(self, out: TextIO, start: float, end: float) -> None:
        self.out, self.start, self.end = out, start, end
        self.began = time.monotonic()
        self.shown = 0.0

    def wrap(self, messages: Iterable[Message]) -> Iterator[Message]:
        try:
            for message in messages:
                now = time.monotonic()
                if now - self.began >= PROGRESS_AFTER and now - self.shown >= PROGRESS_EVERY:
                    self.shown = now
                    done = message.received - self.start
                    length = max(self.end - self.start, 1e-9)
                    self.out.write(
                        f"\r  replayed {done:.1f} of {length:.1f} s ({100 * done / length:.0f}%)"
                    )
                    self.out.flush()
                yield message
        finally:
            self.clear()

    def clear(self) -> None:
        if self.shown:
            self.out.write("\r\033[K")
            self.out.flush()
            self.shown = 0.0


class Printer:
    """The timeline for people: a header, each entry as it happens, a summary."""

    def __init__(self, out: TextIO) -> None:
        self.out = out
        self.tolerance = 0.0  # seconds within which a replay is as live

    def header(self, session: BagReplay) -> None:
        bag, start, end = session.bag, session.start, session.end
        mapped = ", ".join(
            f"{name} → {route.key.removeprefix('topic/')}"
            + (f" (from {route.caller})" if route.caller else "")
            for name, route in session.routes.items()
            if route.key.startswith("topic/")
        )
        self.out.write(
            f"{shown(bag.path)}: {bag.format}, {bag.end - bag.start:.3f} s, {bag.count} "
            f"messages; robot '{session.robot.name}'; {mapped}\n"
        )
        if bag.robot is not None and bag.robot != session.robot.name:
            self.out.write(f"note: recorded of robot '{bag.robot}'\n")
        if start > bag.start or end < bag.end:
            self.out.write(f"window: {start - bag.start:.3f} to {end - bag.start:.3f} s\n")
        for reason in session.replay.skipped:
            self.out.write(f"not replayed: {reason}\n")
        self.out.write(f"{'TIME':>9}  {'WHAT':<11}  DETAIL\n")
        self.out.flush()

    def entry(self, entry: Entry) -> None:
        self.out.write(f"{entry.time:9.3f}  {entry.kind.value:<11}  {entry.describe()}\n")
        self.out.flush()

    def summary(self, timeline: Timeline, counts: MessageCounts, notes: list[str]) -> None:
        out = self.out
        length = timeline.end - timeline.begin
        used = plural(timeline.messages, "message")
        if counts.in_bag != timeline.messages:
            used = f"{timeline.messages} of the bag's {plural(counts.in_bag, 'message')}"
            left = []
            if counts.not_routed:
                topics = ", ".join(counts.not_routed_topics)
                left.append(f"{counts.not_routed} on topics the robot does not watch: {topics}")
            if counts.outside_window:
                left.append(f"{counts.outside_window} outside the window")
            used += f" ({'; '.join(left)})" if left else ""
        out.write(f"\nsummary: {length:.3f} s replayed, {used}\n")
        for note in notes:
            out.write(f"  note: {note}\n")
        for topic in timeline.undecodable:  # replayed without them: the verdict stands
            count = plural(topic.count, "message")
            out.write(f"  undecodable: {topic.topic}: {count} (the first: {topic.reason})\n")
        holds = timeline.holds()
        if not holds:
            out.write("  nothing was diagnosed\n")
        for hold in holds:
            periods = ", ".join(f"{a:.3f}-{b:.3f}" for a, b in hold.periods)
            still = ", still at the end" if hold.held_at_end else ""
            out.write(
                f"  diagnosis {', '.join(hold.diagnosis)}: held {hold.total:.3f} s ({periods}{still})\n"
            )
        fired: dict[tuple[str, str], list[float]] = {}
        for repair in timeline.repairs():
            fired.setdefault((repair.rule, repair.action), []).append(repair.time)
        for (rule, action), times in fired.items():
            when = ", ".join(f"{t:.3f}" for t in times)
            out.write(f"  rule {rule} would {action}: {plural(len(times), 'time')} ({when})\n")
        for hold in timeline.recorded_holds():
            periods = ", ".join(f"{a:.3f}-{b:.3f}" for a, b in hold.periods)
            out.write(
                f"  recorded (live) diagnosis {', '.join(hold.diagnosis)}: held {hold.total:.3f} s "
                f"({periods})\n"
            )
        for entry in timeline.recorded:
            if isinstance(entry, RepairEntry):
                out.write(
                    f"  recorded (live) rule {entry.rule} fired: {entry.action} ({entry.time:.3f})\n"
                )
        if timeline.recorded:
            differences = timeline.differences(self.tolerance)
            if not differences:
                out.write(
                    f"  as live: the same diagnoses and rule firings (within {self.tolerance:.3f} s)\n"
                )
            for difference in differences:
                out.write(f"  not as live: {difference}\n")
