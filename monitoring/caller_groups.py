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

from collections.abc import Callable
from dataclasses import dataclass
from typing import Generic, TypeVar

from executive.bus.session import check_name
from knowledge.errors import BusError
from monitoring.config_entry import Entry

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


def topic_name(entry: Entry, key: str) -> str | None:
    """A topic name usable on the bus (reported if not)."""
    name = entry.text(key, required=True)
    if name is None:
        return None
    try:
        return check_name(name, "topic name")
    except BusError as e:
        entry.error(key, f"{entry.what}: {e}")
        return None


def read_topics(
    owner: Entry, read_settings: Callable[[Entry], S | None]
) -> tuple[TopicGroups[S], ...]:
    """The ``topics`` of an observer entry, each with its caller-id groups."""
    topics: list[TopicGroups[S]] = []
    for entry in owner.entries("topics", f"topic {{n}} of the {owner.what}", required=True):
        if not entry.valid:
            continue
        name = topic_name(entry, "name")
        if name is not None:
            entry.what = f"topic '{name}' of the {owner.what}"
        groups: list[CallerGroup[S]] = []
        if entry.has("callerids"):
            whats = f"caller-id group {{n}} of {entry.what}"
            for group in entry.entries("callerids", whats, required=True):
                if group.valid:
                    callerids = group.names("callerid")
                    settings = read_settings(group)
                    group.close()
                    if settings is not None:
                        groups.append(CallerGroup(callerids, settings))
        else:
            settings = read_settings(entry)
            if settings is not None:
                groups.append(CallerGroup((), settings))
        entry.close()
        seen: set[frozenset[str]] = set()
        for found in groups:
            key = frozenset(found.callerids)
            if key in seen:
                entry.error(
                    "callerids",
                    f"{entry.what} has the caller-id group {list(found.callerids)} twice",
                )
            seen.add(key)
        if name is not None:
            topics.append(TopicGroups(name, tuple(groups)))
    return tuple(topics)
