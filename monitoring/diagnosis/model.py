"""The system description the diagnosis engine reasons about (thesis 5.2.3, 6.3.2).

Nodes subscribe and publish topics; observers watch topics or nodes. The description
changes while the robot runs (ADD, REMOVE, UPDATE, SET as components start and stop);
:meth:`SystemDescription.apply` returns the changed description or raises
:class:`ConfigError` with the reason, so a refused update changes nothing.
"""

from __future__ import annotations

import enum
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

from knowledge.errors import ConfigError, did_you_mean

DEFAULT_BEHAVIOR = "velocity"  # what a movement observer blames when it names no behavior


class ObserverType(enum.Enum):
    """What an observer watches, by its canonical name."""

    FREQUENCY = "frequency"
    TIMEOUT = "timeout"
    TIMESTAMP = "timestamp"
    SCORES = "scores"
    TIMING = "timing"
    MOVEMENT = "movement"
    COMPONENT = "component"
    RESOURCES = "resources"

    def __init__(self, value: str) -> None:
        # an attribute, not a property: the engine asks it for every observer
        self.watches_nodes = value in ("component", "resources")

    @property
    def arity(self) -> tuple[int, int]:
        """The least and most number of resources an observer of this type names."""
        if self is ObserverType.TIMING:
            return (2, 2)
        if self is ObserverType.MOVEMENT:
            return (2, 3)
        return (1, 1)


ALIASES = {
    "hz": ObserverType.FREQUENCY,
    "activated": ObserverType.COMPONENT,
    "value": ObserverType.SCORES,
    "velocity": ObserverType.MOVEMENT,
    "resource": ObserverType.RESOURCES,
}
# every name an observation of a type may carry
SPELLINGS = {t: [t.value] + [a for a, k in ALIASES.items() if k is t] for t in ObserverType}


def observer_type(name: str) -> ObserverType:
    """The type an observer type name (or alias) stands for.

    Raises:
        ConfigError: the name is no observer type.
    """
    found = ALIASES.get(name)
    if found is not None:
        return found
    try:
        return ObserverType(name)
    except ValueError:
        names = [t.value for t in ObserverType] + list(ALIASES)
        raise ConfigError(f"unknown observer type '{name}'{did_you_mean(name, names)}") from None


def _reserved(name: str) -> bool:
    return name.lstrip("/").startswith("AB")


def check_name(name: str, what: str) -> str:
    """A usable node, topic or behavior name (not empty, not starting with ``AB``)."""
    if not name or not name.strip("/"):
        raise ConfigError(f"{what} name is empty")
    if _reserved(name):
        raise ConfigError(f"{what} name '{name}' starts with 'AB' (reserved for the diagnosis)")
    return name


@dataclass(frozen=True)
class Node:
    """A running component with the topics it subscribes and publishes."""

    name: str
    sub_topic: tuple[str, ...] = ()
    pub_topic: tuple[str, ...] = ()

    def to_payload(self) -> dict[str, Any]:
        return {
            "name": self.name,
            "sub_topic": list(self.sub_topic),
            "pub_topic": list(self.pub_topic),
        }


@dataclass(frozen=True)
class ModelObserver:
    """An observer as the diagnosis sees it: a type and the resources it watches.

    ``resource`` is one topic (frequency, timeout, timestamp, scores), one node
    (component, resources), two topics (timing), or two topics and the behavior a
    failure may blame (movement; always three resources once made). ``callerids``
    restricts a topic observer to those publishers (empty: every publisher).
    """

    type: ObserverType
    resource: tuple[str, ...]
    callerids: tuple[str, ...] = ()
    _hash: int = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        # Observers key every lookup of the engine: hash once.
        object.__setattr__(self, "_hash", hash((self.type.value, self.resource, self.callerids)))

    def __hash__(self) -> int:
        return self._hash

    @property
    def spellings(self) -> list[tuple[str, tuple[str, ...], tuple[str, ...]]]:
        """The (type, resource, caller ids) an observation of this observer may carry."""
        names = SPELLINGS[self.type]
        resources = [self.resource]
        if self.behavior == DEFAULT_BEHAVIOR:
            resources.append(self.resource[:2])
        return [(n, r, self.callerids) for n in names for r in resources]

    @classmethod
    def make(
        cls, type_name: str, resource: Sequence[str], callerids: Iterable[str] = ()
    ) -> ModelObserver:
        """An observer in canonical form (alias resolved, default behavior, sorted caller ids).

        Raises:
            ConfigError: unknown type, wrong number of resources, or a bad name.
        """
        kind = observer_type(type_name)
        least, most = kind.arity
        resources = tuple(resource)
        if not least <= len(resources) <= most:
            count = f"{least}" if least == most else f"{least} or {most}"
            raise ConfigError(
                f"a {kind.value} observer watches {count} resources, not {len(resources)} "
                f"({', '.join(resources) or 'none'})"
            )
        what = "node" if kind.watches_nodes else "topic"
        for i, name in enumerate(resources):
            check_name(name, "behavior" if i == 2 else what)
        if kind is ObserverType.MOVEMENT and len(resources) == 2:
            resources = (*resources, DEFAULT_BEHAVIOR)
        ids = tuple(sorted(set(callerids)))
        if ids and kind.watches_nodes:
            raise ConfigError(f"a {kind.value} observer watches a node and takes no caller ids")
        for name in ids:
            check_name(name, "caller id")
        return cls(kind, resources, ids)

    @property
    def topics(self) -> tuple[str, ...]:
        """The topics this observer watches."""
        if self.type.watches_nodes:
            return ()
        return self.resource[:2]

    @property
    def behavior(self) -> str | None:
        return self.resource[2] if self.type is ObserverType.MOVEMENT else None

    def __str__(self) -> str:
        ids = f" from {', '.join(self.callerids)}" if self.callerids else ""
        return f"{self.type.value}[{', '.join(self.resource)}{ids}]"

    def to_payload(self) -> dict[str, Any]:
        payload: dict[str, Any] = {"type": self.type.value, "resource": list(self.resource)}
        if self.callerids:
            payload["callerids"] = list(self.callerids)
        return payload


class UpdateAction(enum.Enum):
    """How a model update changes the system description."""

    ADD = "ADD"  # add new nodes and observers
    REMOVE = "REMOVE"  # remove the named nodes and the given observers
    UPDATE = "UPDATE"  # replace the named (existing) nodes; add the given observers
    SET = "SET"  # replace the whole description


@dataclass(frozen=True)
class ModelUpdate:
    """One change of the system description (the payload of ``diagnosis/model``)."""

    action: UpdateAction
    nodes: tuple[Node, ...] = ()
    observers: tuple[ModelObserver, ...] = ()

    def to_payload(self) -> dict[str, Any]:
        return {
            "action": self.action.value,
            "nodes": [n.to_payload() for n in self.nodes],
            "observers": [o.to_payload() for o in self.observers],
        }

    @classmethod
    def from_payload(cls, payload: Mapping[str, Any]) -> ModelUpdate:
        """Read a request; raises :class:`ConfigError` naming what is malformed."""
        action_name = str(payload.get("action", "")).upper()
        try:
            action = UpdateAction(action_name)
        except ValueError:
            names = ", ".join(a.value for a in UpdateAction)
            raise ConfigError(
                f"unknown model update action '{action_name}' (use {names})"
            ) from None
        nodes = tuple(node_from(entry) for entry in _entries(payload, "nodes"))
        observers = tuple(observer_from(entry) for entry in _entries(payload, "observers"))
        return cls(action, nodes, observers)


def _entries(payload: Mapping[str, Any], key: str) -> list[Mapping[str, Any]]:
    value = payload.get(key, [])
    if not isinstance(value, list) or not all(isinstance(v, Mapping) for v in value):
        raise ConfigError(f"'{key}' must be a list of objects")
    return value


def _names(entry: Mapping[str, Any], key: str) -> tuple[str, ...]:
    value = entry.get(key, [])
    if isinstance(value, str):
        return (value,)
    if not isinstance(value, list) or not all(isinstance(v, str) for v in value):
        raise ConfigError(f"'{key}' must be a list of names, not {value!r}")
    return tuple(value)


def node_from(entry: Mapping[str, Any]) -> Node:
    """A node from ``{name, sub_topic, pub_topic}``."""
    name = entry.get("name")
    if not isinstance(name, str):
        raise ConfigError(f"a node needs a name, not {name!r}")
    return Node(
        check_name(name, "node"),
        tuple(check_name(t, "topic") for t in _names(entry, "sub_topic")),
        tuple(check_name(t, "topic") for t in _names(entry, "pub_topic")),
    )


def observer_from(entry: Mapping[str, Any]) -> ModelObserver:
    """An observer from ``{type, resource, callerids}``."""
    kind = entry.get("type")
    if not isinstance(kind, str):
        raise ConfigError(f"an observer needs a type, not {kind!r}")
    return ModelObserver.make(kind, _names(entry, "resource"), _names(entry, "callerids"))


@dataclass(frozen=True)
class SystemDescription:
    """Nodes and observers; topics are whatever the nodes name."""

    nodes: tuple[Node, ...] = ()
    observers: tuple[ModelObserver, ...] = ()
    _by_name: Mapping[str, Node] = field(init=False, repr=False, compare=False)
    _publishers: Mapping[str, tuple[str, ...]] = field(init=False, repr=False, compare=False)
    _topics: frozenset[str] = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        publishers: dict[str, list[str]] = {}
        for n in self.nodes:
            for topic in n.pub_topic:
                publishers.setdefault(topic, []).append(n.name)
        set_ = object.__setattr__
        set_(self, "_by_name", {n.name: n for n in self.nodes})
        set_(self, "_publishers", {t: tuple(p) for t, p in publishers.items()})
        set_(
            self, "_topics", frozenset(t for n in self.nodes for t in (*n.pub_topic, *n.sub_topic))
        )

    def node(self, name: str) -> Node | None:
        return self._by_name.get(name)

    def publishers(self, topic: str) -> tuple[str, ...]:
        return self._publishers.get(topic, ())

    @property
    def candidates(self) -> tuple[str, ...]:
        """What a diagnosis may name: the nodes, then the behaviors movement observers blame."""
        out = dict.fromkeys(n.name for n in self.nodes)
        out.update(dict.fromkeys(o.behavior for o in self.observers if o.behavior))
        return tuple(out)

    def problem(self, observer: ModelObserver) -> str | None:
        """Why an observer does not fit these nodes, or ``None`` if it does."""
        if observer.type.watches_nodes:
            name = observer.resource[0]
            if name not in self._by_name:
                return f"observer {observer} watches unknown node '{name}'{did_you_mean(name, self._by_name)}"
            return None
        for topic in observer.topics:
            if not self.publishers(topic):
                if topic in self._topics:
                    return f"observer {observer} watches topic '{topic}' that no node publishes"
                hint = did_you_mean(topic, sorted(self._topics))
                return f"observer {observer} watches unknown topic '{topic}'{hint}"
            for caller in observer.callerids:
                if caller not in self._by_name:
                    return f"observer {observer} names unknown caller id '{caller}'"
        for caller in observer.callerids:
            if not any(caller in self.publishers(t) for t in observer.topics):
                return f"observer {observer} names caller id '{caller}' that publishes none of its topics"
        return None

    def problems(self) -> list[tuple[Node | ModelObserver, str]]:
        """Everything wrong with this description, each with what it is about."""
        out: list[tuple[Node | ModelObserver, str]] = []
        seen: set[str] = set()
        for node in self.nodes:
            if node.name in seen:
                out.append((node, f"node '{node.name}' is already in the model"))
            seen.add(node.name)
        observers: set[ModelObserver] = set()
        for observer in self.observers:
            if observer in observers:
                out.append((observer, f"observer {observer} is already in the model"))
            observers.add(observer)
            reason = self.problem(observer)
            if reason:
                out.append((observer, reason))
        return out

    def apply(self, update: ModelUpdate) -> SystemDescription:
        """The description after an update.

        Raises:
            ConfigError: the update is invalid (the reason names the node or observer).
        """
        nodes = list(self.nodes)
        observers = list(self.observers)
        if update.action is UpdateAction.SET:
            nodes, observers = list(update.nodes), list(update.observers)
        elif update.action is UpdateAction.ADD:
            nodes += update.nodes
            observers += update.observers
        elif update.action is UpdateAction.UPDATE:
            replaced = {n.name: n for n in update.nodes}
            for name in replaced:
                self._known(name)
            nodes = [replaced.get(n.name, n) for n in nodes]
            observers += update.observers
        else:
            gone = {self._known(n.name).name for n in update.nodes}
            for observer in update.observers:
                if observer not in observers:
                    raise ConfigError(f"observer {observer} is not in the model")
                observers.remove(observer)
            nodes = [n for n in nodes if n.name not in gone]
        result = SystemDescription(tuple(nodes), tuple(observers))
        problems = result.problems()
        if problems:
            raise ConfigError(problems[0][1])
        return result

    def _known(self, name: str) -> Node:
        node = self._by_name.get(name)
        if node is None:
            raise ConfigError(f"unknown node '{name}'{did_you_mean(name, self._by_name)}")
        return node

    def to_payload(self) -> dict[str, Any]:
        return {
            "nodes": [n.to_payload() for n in self.nodes],
            "observers": [o.to_payload() for o in self.observers],
        }
