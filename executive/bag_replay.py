"""A recording opened and routed to a robot, ready to replay through its monitoring:
what ``dura replay`` runs, and the ``dura_replay`` fixture
(:func:`executive.testing.replay.replay_bag`).

It composes the bag readers (:mod:`executive.bags`) and the offline replay of
monitoring (:mod:`monitoring.replay`); it lives beside them, not in
:mod:`executive.testing`, so that ``dura replay`` starts without pytest.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Iterator, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from executive.bags.bag import Bag, Route, routes
from executive.bags.reader import open_bag, read_types
from executive.bus.keys import OBSERVATIONS
from executive.bus.message import Message
from knowledge.description import RobotDescription
from knowledge.errors import BagError, BusError
from knowledge.robot import load_robot
from monitoring.replay import Replay, state_component, watched_topics
from monitoring.timeline import Entry, Timeline


@dataclass(frozen=True)
class MessageCounts:
    """How a replay used the bag's messages: those it holds, those on topics routed to
    the robot, and of them those replayed (the others were outside the window)."""

    in_bag: int
    routed: int
    replayed: int
    not_routed_topics: tuple[str, ...] = ()  # topics with messages the robot does not watch

    @property
    def not_routed(self) -> int:
        return self.in_bag - self.routed

    @property
    def outside_window(self) -> int:
        return self.routed - self.replayed

    def to_payload(self) -> dict[str, Any]:
        return {
            "in_bag": self.in_bag,
            "routed": self.routed,
            "replayed": self.replayed,
            "outside_window": self.outside_window,
            "not_routed": self.not_routed,
            "not_routed_topics": list(self.not_routed_topics),
        }


class BagReplay:
    """An opened recording, routed to a robot and ready to replay (close it when done).

    Args:
        path: the recording.
        robot: the robot description (or its file).
        maps: ``BAG_TOPIC=TOPIC`` routes besides the same names.
        begin, end: the window, in seconds since the recording's start.
        on_entry: called with each timeline entry as it happens.
        types: folders or files of ``.msg`` definitions for types the bag does not define.

    Raises:
        BagError: the recording is unreadable, a map is wrong, or nothing maps.
        ConfigError: the robot description is invalid.
    """

    def __init__(
        self,
        path: Path,
        robot: RobotDescription | Path,
        *,
        maps: Sequence[str] = (),
        begin: float | None = None,
        end: float | None = None,
        on_entry: Callable[[Entry], None] | None = None,
        types: Sequence[Path] = (),
    ) -> None:
        self.robot = (
            robot if isinstance(robot, RobotDescription) else load_robot(robot, domain=False)
        )
        self.bag: Bag = open_bag(Path(path), read_types(types) if types else None)
        try:
            self.start_ns, self.end_ns = self._window(begin, end)
            found = routes(self.bag, self.robot, maps, watched=watched_topics(self.robot))
            self.replay = Replay(
                self.robot,
                provided={r.key for r in found.values()},
                origin_ns=self.bag.start_ns,
                start_ns=self.start_ns,
                on_entry=on_entry,
                loops=self._live_loops(),
                undecodable=self.bag.undecodable,
            )
            listened = self.replay.listened
            self.routes: dict[str, Route] = {
                name: route
                for name, route in found.items()
                if route.key in listened or state_component(route.key) is not None
            }
        except BaseException:
            self.bag.close()
            raise

    def _live_loops(self) -> dict[str, list[int]]:
        """When each observer looped in the recorded run (a dura recording's
        observations, in ns), so that the replay's loops are the live ones."""
        bag = self.bag
        if not bag.keys_are_bus_keys or OBSERVATIONS not in {t.name for t in bag.topics}:
            return {}
        loops: dict[str, set[int]] = {}
        for message in bag.messages({OBSERVATIONS: Route(OBSERVATIONS)}):
            try:
                payload = message.payload
                stamp = round(float(payload["stamp"]) * 1e9)  # the bus has it in seconds
                loops.setdefault(str(payload["observer"]), set()).add(stamp)
            except BusError:  # a malformed observation: that loop is not known (counted)
                continue
            except (KeyError, TypeError, ValueError) as e:
                why = f"not an observation ({type(e).__name__}: {e})"
                bag.undecodable.add(OBSERVATIONS, why)
        return {observer: sorted(times) for observer, times in loops.items()}

    @property
    def start(self) -> float:
        """The window's start, in seconds (the recording's time)."""
        return self.start_ns / 1e9

    @property
    def end(self) -> float:
        """The window's end, in seconds (the recording's time)."""
        return self.end_ns / 1e9

    def _window(self, begin: float | None, end: float | None) -> tuple[int, int]:
        """Return the window in integer nanoseconds: the first and last message's
        times, or ``begin`` and ``end`` seconds after the first."""
        bag = self.bag
        length = bag.end_ns - bag.start_ns
        if begin is not None and round(begin * 1e9) > length:
            raise BagError(f"{bag.path}: --from {begin:g} is after its end ({length / 1e9:.3f} s)")
        if begin is not None and end is not None and end <= begin:
            raise BagError(f"--to {end:g} must come after --from {begin:g}")
        start = bag.start_ns + round((begin or 0.0) * 1e9)
        stop = bag.end_ns if end is None else min(bag.end_ns, bag.start_ns + round(end * 1e9))
        return start, stop

    def messages(self) -> Iterator[Message]:
        """Yield the routed messages of the window, in order."""
        return self.bag.messages(self.routes, self.start_ns, self.end_ns)

    def run(self, messages: Iterable[Message] | None = None) -> Timeline:
        """Replay ``messages`` (default: :meth:`messages`) and return the timeline."""
        return self.replay.run(self.messages() if messages is None else messages, self.end_ns)

    def counts(self, timeline: Timeline) -> MessageCounts:
        """How the bag's messages were used by a replay of it."""
        return MessageCounts(
            in_bag=self.bag.count,
            routed=sum(t.count for t in self.bag.topics if t.name in self.routes),
            replayed=timeline.messages,
            not_routed_topics=tuple(
                t.name for t in self.bag.topics if t.name not in self.routes and t.count
            ),
        )

    def close(self) -> None:
        self.bag.close()

    def __enter__(self) -> BagReplay:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
