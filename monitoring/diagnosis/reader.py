"""Read a diagnosis model and a set of observations from YAML (``dura diagnose``).

MODEL.yaml: ``nodes: [{name, sub_topic, pub_topic}]`` and ``observers:`` (or
``observations:``) ``[{type, resource: [...], callerids: [...]}]``. The tug form is
accepted too: ``topics: [a, b]`` (or ``[[a, b]]`` for timing and movement) and
``nodes: [n1, n2]`` stand for one observer per entry.

OBS.yaml: ``observations: [{type, resource: [...], observation: <int>}]``; a negative
observation is a fault. Every error is a :class:`ConfigError` ``file:line: reason``.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Annotated, Any

from executive.bus.payloads import ObservationInfo
from knowledge.conventions import Check, Convert, OneOrMore
from knowledge.errors import ConfigError, DuraError, located
from knowledge.finding import Report
from knowledge.typed_reader import MISSING, Entry, Place, open_entry
from knowledge.yamlsource import DocumentSource, read_file
from monitoring.diagnosis.model import ModelObserver, Node, SystemDescription, check_name

Texts = Annotated[tuple[str, ...], OneOrMore()]


def _raise_first(report: Report) -> None:
    if report.errors:
        raise ConfigError(str(report.errors[0]))


def _top(path: Path, report: Report) -> Entry:
    found = read_file(path, report)
    _raise_first(report)
    if found is None:
        raise ConfigError(located(path, None, "is empty"))
    top = open_entry(found.value, DocumentSource(found, report), what="the file")
    _raise_first(report)  # not a mapping
    if top is None:
        raise ConfigError(located(path, None, "is not a mapping"))
    return top


def _each(read_one: Callable[[Any, Place], None]) -> Any:
    """A list whose items ``read_one`` reads (each in its place)."""

    def item(value: Any, place: Place) -> Any:
        read_one(value, place)
        return MISSING

    return tuple[Annotated[Any, Convert(item)], ...]


def _names(what: str) -> Any:
    """Names of a kind (``topic``), each checked: a wrong one is reported at its key."""

    def checked(name: str, place: Place) -> Any:
        try:
            return check_name(name, what)
        except DuraError as e:
            place.entry.error(place.key, str(e))
            return MISSING

    return Annotated[tuple[Annotated[str, Check(checked)], ...], OneOrMore()]


def _resource(value: Any, place: Place) -> Any:
    """The resources of one observer of a tug entry: a name, or a list of names."""
    if isinstance(value, Mapping):
        return place.wrong("a name", value)
    if isinstance(value, list):
        return [place.source.text(v, (*place.path, i)) or str(v) for i, v in enumerate(value)]
    return [place.source.text(value, place.path) or str(value)]


def _observer_entries(entry: Entry) -> list[tuple[str, list[str], list[str]]]:
    """(type, resources, caller ids) of each observer an entry stands for."""
    kind = entry.read("type", str, None, required=True) or ""
    callerids = list(entry.read("callerids", Texts, ()))
    if entry.has("resource"):
        return [(kind, list(entry.read("resource", Texts, ())), callerids)]
    out: list[tuple[str, list[str], list[str]]] = []
    resources = tuple[Annotated[Any, Convert(_resource)], ...]
    for key in ("topics", "nodes"):
        out += [(kind, names, callerids) for names in entry.read(key, resources, ())]
    if not out and not entry.has("topics") and not entry.has("nodes"):
        entry.error(None, f"{entry.what} has no 'resource'")
    return out


def read_model(path: Path) -> SystemDescription:
    """Read MODEL.yaml; raises :class:`ConfigError` at the first problem."""
    report = Report(str(path))
    top = _top(path, report)
    nodes: list[Node] = []

    def node(value: Any, place: Place) -> None:
        entry = open_entry(value, place.source, place.path, "node", place=place)
        if entry is None:
            return
        name = entry.read("name", str, None, required=True)
        topics = _names("topic")
        found = Node(
            name or "", entry.read("sub_topic", topics, ()), entry.read("pub_topic", topics, ())
        )
        entry.close()
        if name is None:
            return
        try:
            check_name(name, "node")
        except DuraError as e:
            entry.error(None, str(e))
        if any(n.name == name for n in nodes):
            entry.error(None, f"node '{name}' is already in the model")
        nodes.append(found)

    top.read("nodes", _each(node), ())
    _raise_first(report)
    model = SystemDescription(tuple(nodes))
    observers: list[ModelObserver] = []

    def observer(value: Any, place: Place) -> None:
        entry = open_entry(value, place.source, place.path, "observer", place=place)
        if entry is None:
            return
        for kind, resources, callerids in _observer_entries(entry):
            try:
                found = ModelObserver.make(kind, resources, callerids)
            except DuraError as e:
                entry.error(None, str(e))
                continue
            reason = model.problem(found)
            if found in observers:
                reason = f"observer {found} is already in the model"
            if reason:
                entry.error(None, reason)
            observers.append(found)
        entry.close()

    key = "observations" if top.has("observations") and not top.has("observers") else "observers"
    top.read(key, _each(observer), ())
    top.close()
    _raise_first(report)
    return SystemDescription(model.nodes, tuple(observers))


def read_observations(path: Path, model: SystemDescription) -> list[ObservationInfo]:
    """Read OBS.yaml; every observation must come from an observer of the model."""
    report = Report(str(path))
    top = _top(path, report)
    known = set(model.observers)
    out: list[ObservationInfo] = []

    def observation(value: Any, place: Place) -> None:
        entry = open_entry(value, place.source, place.path, "observation", place=place)
        if entry is None:
            return
        kind = entry.read("type", str, None, required=True) or ""
        resources = entry.read("resource", Texts, (), required=True)
        callerids = entry.read("callerids", Texts, ())
        number = entry.read("observation", int, 0)
        if not entry.has("observation"):
            entry.error(None, "observation has no 'observation' (a number; negative is a fault)")
        message = entry.read("observation_msg", str, "") or ""
        entry.close()
        try:
            observer = ModelObserver.make(kind, resources, callerids)
        except DuraError as e:
            entry.error(None, str(e))
            return
        if observer not in known:
            entry.error(None, f"observation of {observer}: no such observer in the model")
        out.append(ObservationInfo(kind, tuple(resources), number, message, callerids=callerids))

    top.read("observations", _each(observation), ())
    top.close()
    _raise_first(report)
    return out
