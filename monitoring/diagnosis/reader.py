"""Read a diagnosis model and a set of observations from YAML (``dura diagnose``).

MODEL.yaml: ``nodes: [{name, sub_topic, pub_topic}]`` and ``observers:`` (or
``observations:``) ``[{type, resource: [...], callerids: [...]}]``. The tug form is
accepted too: ``topics: [a, b]`` (or ``[[a, b]]`` for timing and movement) and
``nodes: [n1, n2]`` stand for one observer per entry.

OBS.yaml: ``observations: [{type, resource: [...], observation: <int>}]``; a negative
observation is a fault. Every error is a :class:`ConfigError` ``file:line: reason``.
"""

from __future__ import annotations

from pathlib import Path

import yaml

from executive.bus.payloads import ObservationInfo
from knowledge.errors import ConfigError, DuraError, located
from knowledge.finding import Report
from knowledge.yamlsource import Section, compose, describe, line_of
from monitoring.diagnosis.model import ModelObserver, Node, SystemDescription, check_name


def _raise_first(report: Report) -> None:
    if report.errors:
        raise ConfigError(str(report.errors[0]))


def _top(path: Path, report: Report) -> Section:
    node = compose(path, report)
    _raise_first(report)
    if node is None:
        raise ConfigError(located(path, None, "is empty"))
    return Section(node, "the file", report)


def _names(entry: Section, key: str, what: str) -> tuple[str, ...]:
    out: list[str] = []
    for name in entry.texts(key):
        try:
            out.append(check_name(name, what))
        except DuraError as e:
            entry.report.error(entry.key_line(key), str(e))
    return tuple(out)


def _observer_entries(entry: Section) -> list[tuple[str, list[str], list[str]]]:
    """(type, resources, caller ids) of each observer an entry stands for."""
    kind = entry.text("type", required=True) or ""
    callerids = list(entry.texts("callerids"))
    if entry.has("resource"):
        return [(kind, list(entry.texts("resource")), callerids)]
    out: list[tuple[str, list[str], list[str]]] = []
    for key in ("topics", "nodes"):
        for item in entry.sequence(key):
            if isinstance(item, yaml.ScalarNode):
                out.append((kind, [str(item.value)], callerids))
            elif isinstance(item, yaml.SequenceNode):
                out.append((kind, [str(v.value) for v in item.value], callerids))
            else:
                entry.report.error(
                    line_of(item), f"'{key}' of {entry.what} must list names, not {describe(item)}"
                )
    if not out and not entry.has("topics") and not entry.has("nodes"):
        entry.report.error(entry.line, f"{entry.what} has no 'resource'")
    return out


def read_model(path: Path) -> SystemDescription:
    """Read MODEL.yaml; raises :class:`ConfigError` at the first problem."""
    report = Report(str(path))
    top = _top(path, report)
    nodes: list[Node] = []
    for item in top.sequence("nodes"):
        entry = Section(item, "node", report)
        if not entry.valid:
            continue
        name = entry.text("name", required=True)
        node = Node(
            name or "", _names(entry, "sub_topic", "topic"), _names(entry, "pub_topic", "topic")
        )
        entry.close()
        if name is None:
            continue
        try:
            check_name(name, "node")
        except DuraError as e:
            report.error(entry.line, str(e))
        if any(n.name == name for n in nodes):
            report.error(entry.line, f"node '{name}' is already in the model")
        nodes.append(node)
    _raise_first(report)
    model = SystemDescription(tuple(nodes))
    observers: list[ModelObserver] = []
    key = "observations" if top.has("observations") and not top.has("observers") else "observers"
    for item in top.sequence(key):
        entry = Section(item, "observer", report)
        if not entry.valid:
            continue
        for kind, resources, callerids in _observer_entries(entry):
            try:
                observer = ModelObserver.make(kind, resources, callerids)
            except DuraError as e:
                report.error(entry.line, str(e))
                continue
            reason = model.problem(observer)
            if observer in observers:
                reason = f"observer {observer} is already in the model"
            if reason:
                report.error(entry.line, reason)
            observers.append(observer)
        entry.close()
    top.close()
    _raise_first(report)
    return SystemDescription(model.nodes, tuple(observers))


def read_observations(path: Path, model: SystemDescription) -> list[ObservationInfo]:
    """Read OBS.yaml; every observation must come from an observer of the model."""
    report = Report(str(path))
    top = _top(path, report)
    known = set(model.observers)
    out: list[ObservationInfo] = []
    for item in top.sequence("observations"):
        entry = Section(item, "observation", report)
        if not entry.valid:
            continue
        kind = entry.text("type", required=True) or ""
        resources = entry.texts("resource", required=True)
        callerids = entry.texts("callerids")
        value = entry.integer("observation", 0)
        if not entry.has("observation"):
            report.error(
                entry.line, "observation has no 'observation' (a number; negative is a fault)"
            )
        message = entry.text("observation_msg", "") or ""
        entry.close()
        try:
            observer = ModelObserver.make(kind, resources, callerids)
        except DuraError as e:
            report.error(entry.line, str(e))
            continue
        if observer not in known:
            report.error(entry.line, f"observation of {observer}: no such observer in the model")
        out.append(
            ObservationInfo(kind, tuple(resources), value, message, callerids=tuple(callerids))
        )
    top.close()
    _raise_first(report)
    return out
