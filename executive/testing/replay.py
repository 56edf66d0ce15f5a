"""A recording replayed through a robot's monitoring: monitoring in the loop.

:func:`replay_bag` opens a recording (a ROS 2 bag or a ``dura record`` MCAP file),
routes its topics to the robot description's, and replays it through the robot's
observers, diagnosis and repair rules (:mod:`monitoring.replay`) with the recording's
time as the clock; it returns the :class:`monitoring.timeline.Timeline`, deterministic,
so that a test can pin what a recorded incident must be diagnosed as::

    def test_the_lidar_dropout_of_tuesday_is_diagnosed(dura_replay):
        timeline = dura_replay("bags/lidar_dropout", "robot.yaml")
        assert timeline.diagnosed() == [("lidar",)]
        assert [r.action for r in timeline.repairs()] == ["restart lidar"]

``dura replay`` runs the same :class:`BagReplay`.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Iterator, Sequence
from pathlib import Path

from executive.bags.bag import Bag, Route, routes
from executive.bags.reader import open_bag
from executive.bus.session import Message
from knowledge.description import RobotDescription
from knowledge.errors import BagError
from knowledge.robot import load_robot
from monitoring.replay import Replay, state_component, watched_topics
from monitoring.timeline import Entry, Timeline


class BagReplay:
    """An opened recording, routed to a robot and ready to replay (close it when done).

    Args:
        path: the recording.
        robot: the robot description (or its file).
        maps: ``BAG_TOPIC=TOPIC`` routes besides the same names.
        begin, end: the window, in seconds since the recording's start.
        on_entry: called with each timeline entry as it happens.

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
    ) -> None:
        self.robot = robot if isinstance(robot, RobotDescription) else load_robot(robot)
        self.bag: Bag = open_bag(Path(path))
        try:
            self.start, self.end = self._window(begin, end)
            found = routes(self.bag, self.robot, maps, watched=watched_topics(self.robot))
            self.replay = Replay(
                self.robot,
                provided={r.key for r in found.values()},
                origin=self.bag.start,
                start=self.start,
                on_entry=on_entry,
            )
            listened = self.replay.listened
            self.routes: dict[str, Route] = {
                name: route
                for name, route in found.items()
                if route.key in listened or state_component(route.key) is not None
            }
            self.bag.check(self.routes)
        except BaseException:
            self.bag.close()
            raise

    def _window(self, begin: float | None, end: float | None) -> tuple[float, float]:
        bag = self.bag
        length = bag.end - bag.start
        if begin is not None and begin > length:
            raise BagError(f"{bag.path}: --from {begin:g} is after its end ({length:.3f} s)")
        if begin is not None and end is not None and end <= begin:
            raise BagError(f"--to {end:g} must come after --from {begin:g}")
        start = bag.start + (begin or 0.0)
        return start, min(bag.end, bag.start + end) if end is not None else bag.end

    def messages(self) -> Iterator[Message]:
        """Yield the routed messages of the window, in order."""
        return self.bag.messages(self.routes, self.start, self.end)

    def run(self, messages: Iterable[Message] | None = None) -> Timeline:
        """Replay ``messages`` (default: :meth:`messages`) and return the timeline."""
        return self.replay.run(self.messages() if messages is None else messages, self.end)

    def close(self) -> None:
        self.bag.close()

    def __enter__(self) -> BagReplay:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


def replay_bag(
    path: str | Path,
    robot: str | Path | RobotDescription,
    *,
    maps: Sequence[str] = (),
    begin: float | None = None,
    end: float | None = None,
) -> Timeline:
    """Replay a recording through a robot's observers, diagnosis and repair rules and
    return the timeline (see the module docstring)."""
    description = robot if isinstance(robot, RobotDescription) else Path(robot)
    with BagReplay(Path(path), description, maps=maps, begin=begin, end=end) as replay:
        return replay.run()
