"""An opened recording: its topics and its messages as bus messages, and how its topics
map to a robot's.

A recording is a ROS 2 bag (rosbag2: a folder with ``metadata.yaml``, or one ``.mcap``
or ``.db3`` file) or an MCAP file of a dura run (``dura record``). Its messages become
:class:`executive.bus.session.Message` objects as observers receive them live: the
recording's receive time as ``received``, its publish time as ``sent`` where it has
one, the publisher's name as caller id where it has one, and a payload decoded only
when read.

Each recorded topic is *routed* to a bus key. A ROS 2 topic goes to the robot
description's topic of the same name (its leading slash dropped: ``/scan`` is
``scan``), or to the one ``--map BAG_TOPIC=TOPIC`` names; a dura recording's channels
are bus keys already (``topic/scan``, ``resources``, ``component/lidar/state``). A
message without a caller id gets the one component of the robot that publishes its
topic, if there is exactly one.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Callable, Collection, Iterator, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path

from executive.bus.keys import DIAGNOSES, EVENTS, RESOURCES, topic
from executive.bus.message import Message
from executive.bus.undecodable import UndecodableMessages
from knowledge.description import RobotDescription
from knowledge.errors import BagError, did_you_mean

DURA_PROFILE = "dura"  # the MCAP profile of dura's recordings
DURA_KEYS = (RESOURCES, DIAGNOSES, EVENTS)  # replayed as they are, besides topics and states


@dataclass(frozen=True)
class BagTopic:
    """One recorded topic (a channel of an MCAP file, a topic of a rosbag2)."""

    name: str  # as recorded: /scan, or a bus key in a dura recording: topic/scan
    type: str  # a ROS 2 message type, or the JSON schema's name
    count: int = 0
    callers: tuple[str, ...] = ()  # publishers the recording names (dura recordings)


@dataclass(frozen=True)
class Route:
    """Where the messages of a recorded topic go: a bus key, with a caller id for
    messages that have none."""

    key: str
    caller: str = ""


@dataclass
class Bag(ABC):
    """An opened recording; close it (or use it as a context manager) when done."""

    path: Path
    format: str  # "rosbag2 (mcap)", "rosbag2 (sqlite3)", "dura recording (mcap)"
    start_ns: int = 0  # the first message's receive time, in ns (from the messages)
    end_ns: int = 0  # the last message's receive time, in ns
    topics: tuple[BagTopic, ...] = ()
    robot: str | None = None  # the robot a dura recording is of
    keys_are_bus_keys: bool = False  # a dura recording: topics are bus keys
    notes: list[str] = field(default_factory=list)  # what was not read, each in one line
    # its messages that did not decode, per recorded topic (counted as they are read)
    undecodable: UndecodableMessages = field(default_factory=UndecodableMessages)

    @property
    def start(self) -> float:
        """The first message's receive time, in seconds."""
        return self.start_ns / 1e9

    @property
    def end(self) -> float:
        """The last message's receive time, in seconds."""
        return self.end_ns / 1e9

    def __enter__(self) -> Bag:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def close(self) -> None:  # noqa: B027 - an optional hook
        """Release the files."""

    @property
    def count(self) -> int:
        return sum(t.count for t in self.topics)

    @abstractmethod
    def messages(
        self, routes: Mapping[str, Route], start: int | None = None, end: int | None = None
    ) -> Iterator[Message]:
        """Yield the messages of the routed topics from ``start`` to ``end`` (integer
        nanoseconds, both included) in order of reception, after the component states
        before ``start`` (they say which components run when the window opens).

        A message whose type the bag does not define is still yielded (observers that
        do not decode it use its times); decoding it fails, and :attr:`notes` says so
        once per topic. Each message that fails to decode (or to decompress) is counted
        in :attr:`undecodable` under its recorded topic, once.

        Raises:
            BagError: the file is corrupt, or a routed topic unreadable.
        """

    def counter(self, topic: str) -> Callable[[str], None]:
        """Return how to count an undecodable message of a recorded topic, with the reason."""
        undecodable = self.undecodable

        def count(reason: str) -> None:
            undecodable.add(topic, reason)

        return count

    def note(self, text: str) -> None:
        """Say once why something of the bag was not read."""
        if text not in self.notes:
            self.notes.append(text)


def _bag_topic(bag: Bag, name: str) -> BagTopic | None:
    names = {t.name: t for t in bag.topics}
    return names.get(name) or names.get("/" + name.lstrip("/")) or names.get(name.lstrip("/"))


def robot_topic(bag: Bag, name: str) -> str | None:
    """Return the robot topic a recorded topic goes to by default (its name), if any."""
    if bag.keys_are_bus_keys:
        return name.removeprefix("topic/") if name.startswith("topic/") else None
    return name.strip("/") or None


def routes(
    bag: Bag,
    robot: RobotDescription,
    maps: Sequence[str] = (),
    *,
    watched: Collection[str] = (),
) -> dict[str, Route]:
    """Route each recorded topic to a bus key (see the module docstring).

    Args:
        maps: ``BAG_TOPIC=TOPIC`` pairs that route a recorded topic to a robot topic.
        watched: topics the robot's observers watch, besides its components' topics.

    Raises:
        BagError: a map names a topic the bag or the robot does not have, or no topic
            of the bag goes to a topic of the robot.
    """
    known = set(robot.topics) | set(watched)
    publishers: dict[str, list[str]] = {}
    for component in robot.components.values():
        for name in component.publishes:
            publishers.setdefault(name, []).append(component.name)
    where = str(bag.path)
    chosen: dict[str, str] = {}
    for pair in maps:
        source, sep, wanted = pair.partition("=")
        wanted = wanted.strip().strip("/")
        if not sep or not source.strip() or not wanted:
            raise BagError(f"--map {pair}: write BAG_TOPIC=TOPIC, e.g. /front/scan=scan")
        found = _bag_topic(bag, source.strip())
        if found is None:
            names = [t.name for t in bag.topics]
            raise BagError(
                f"{where}: no topic '{source}' to map{did_you_mean(source, names)} "
                f"(it has {', '.join(names) or 'none'})"
            )
        if wanted not in known:
            raise BagError(
                f"--map {pair}: robot '{robot.name}' has no topic '{wanted}'"
                f"{did_you_mean(wanted, sorted(known))}"
            )
        chosen[found.name] = wanted
    found_routes: dict[str, Route] = {}
    for recorded in bag.topics:
        target = chosen.get(recorded.name) or robot_topic(bag, recorded.name)
        if target is not None and target in known:
            only = publishers.get(target, [])
            found_routes[recorded.name] = Route(topic(target), only[0] if len(only) == 1 else "")
    if not found_routes:
        listed = ", ".join(t.name for t in bag.topics) or "none"
        raise BagError(
            f"{where}: none of its topics ({listed}) is a topic of robot '{robot.name}' "
            f"({', '.join(sorted(known)) or 'none'}); map them with --map BAG_TOPIC=TOPIC"
        )
    if bag.keys_are_bus_keys:
        for recorded in bag.topics:
            name = recorded.name
            if name in DURA_KEYS or (name.startswith("component/") and name.endswith("/state")):
                found_routes[name] = Route(name)
    return found_routes
