"""Topics watched per caller-id group (thesis 6.2.5), shared by the frequency, timeout
and timestamp observers.

Every bus message carries its publisher's component name as caller id. A topic entry
lists caller-id groups; each group has its own settings (filter, states, timeout, ...)
and reports on its own::

    topics:
      - name: scan
        callerids:
          - callerid: []             # every publisher of the topic together
            filter: {type: mean, window_size: 10}
            states: [...]
          - callerid: [lidar]        # only what 'lidar' publishes
            ...

Without ``callerids`` the topic entry itself holds the settings of one group of
every publisher. Leading slashes of ROS names (``/scan``, ``/nodeA``) are dropped.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Annotated, Any, Generic, TypeVar

from executive.bus.session import check_name
from knowledge.conventions import Check, Convert, Label, Names
from knowledge.errors import BusError
from knowledge.typed_reader import MISSING, Place, open_entry, read_inline, read_value
from monitoring.filter import Text

S = TypeVar("S")


@dataclass(frozen=True)
class CallerGroup(Generic[S]):
    """A set of publishers (empty: all of them) and the settings that watch them."""

    callerids: tuple[str, ...]
    settings: S

    def includes(self, caller: str) -> bool:
        return not self.callerids or caller in self.callerids


@dataclass(frozen=True)
class TopicGroups(Generic[S]):
    name: str
    groups: tuple[CallerGroup[S], ...]


def _bus_name(name: str, place: Place) -> Any:
    try:
        return check_name(name, "topic name")
    except BusError as e:
        place.entry.error(place.key, f"{place.entry.what}: {e}")
        return MISSING


TopicName = Annotated[Text, Check(_bus_name)]
"""A topic name usable on the bus (reported if not)."""

CallerIds = Annotated[tuple[str, ...], Names()]


def topics_with(settings: type[S]) -> Convert:
    """How the ``topics`` of an observer entry are read (``Annotated`` metadata of a
    ``tuple[TopicGroups[S], ...]``) whose caller-id groups have ``settings``: a
    dataclass read from the keys of the group (or of the topic, without groups)."""

    def read_topic(value: Any, place: Place) -> Any:
        entry = open_entry(value, place.source, place.path, place.label or "", place=place)
        if entry is None:
            return MISSING
        name = entry.read("name", TopicName, None, required=True)
        if name is not None:
            entry.what = f"topic '{name}' of the {entry.owner}"
        groups: list[CallerGroup[S]] = []
        if entry.has("callerids"):
            each = Annotated[
                tuple[Annotated[Any, Convert(read_group)], ...],
                Label("caller-id group {n} of {what}"),
            ]
            groups = list(entry.read("callerids", each, (), required=True))
        else:
            found = read_inline(settings, entry)
            if found is not MISSING:
                groups.append(CallerGroup((), found))
        entry.close()
        seen: set[frozenset[str]] = set()
        for group in groups:
            key = frozenset(group.callerids)
            if key in seen:
                entry.error(
                    "callerids",
                    f"{entry.what} has the caller-id group {list(group.callerids)} twice",
                )
            seen.add(key)
        return TopicGroups(name, tuple(groups)) if name is not None else MISSING

    def read_group(value: Any, place: Place) -> Any:
        entry = open_entry(value, place.source, place.path, place.label or "", place=place)
        if entry is None:
            return MISSING
        callerids = entry.read("callerid", CallerIds, ())
        found = read_inline(settings, entry)
        entry.close()
        return CallerGroup(callerids, found) if found is not MISSING else MISSING

    each = Annotated[
        tuple[Annotated[Any, Convert(read_topic)], ...], Label("topic {n} of the {what}")
    ]

    def read_topics(value: Any, place: Place) -> Any:
        return read_value(each, value, place)

    return Convert(read_topics)
