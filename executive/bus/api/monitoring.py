"""The monitoring services' API: observers at run time (the observer manager), the
diagnosis model and exoneration (the diagnosis engine)."""

from __future__ import annotations

from dataclasses import field
from typing import Any

from executive.bus.api.free_form import ObserverConfig
from executive.bus.keys import DIAGNOSIS_EXONERATION, DIAGNOSIS_MODEL, observers_api
from executive.bus.schema import Payload, Text
from executive.bus.verb import Empty, Verb
from knowledge.record_class import record


@record
class ObserverStatus:
    """What the observer manager says about one observer: its id, type and component
    (``None``: an observer of its own), whether it is enabled and observes now
    (``active``: enabled, and its component READY), and its rates."""

    id: str
    type: str
    component: str | None
    enabled: bool
    active: bool
    main_loop_rate: float
    start_up_time: float


@record
class ObserversReply(Payload):
    """Each observer."""

    observers: list[ObserverStatus]


@record
class ObserverAdd(Payload):
    """An observer entry (the thesis/tug schema), of a component or of its own, with an
    optional name (its id)."""

    config: ObserverConfig
    component: str | None = None
    name: str | None = None


@record
class ObserverChange(Payload):
    """A new configuration for an observer (it keeps its id)."""

    id: Text
    config: ObserverConfig


@record
class ObserverId(Payload):
    """An observer, by id (``<component>/<index>`` for those of the robot description)."""

    id: Text


@record
class ObserverActive(Payload):
    """Whether the observer observes now (enabled, and its component READY)."""

    id: str
    active: bool


@record
class LatestReply(Payload):
    """The last observation of every resource of every active observer, as published on
    ``observations``."""

    observations: list[dict[str, Any]]


@record
class ModelChange(Payload):
    """A change of the diagnosis model: ADD, REMOVE, UPDATE, SET or GET, with nodes
    ``{name, sub_topic, pub_topic}`` and observers ``{type, resource, callerids}``."""

    action: Text
    nodes: list[dict[str, Any]] = field(default_factory=list)
    observers: list[dict[str, Any]] = field(default_factory=list)


@record
class ModelReply(Payload):
    """The model after the change, or why the change was refused (it changed nothing)."""

    ok: bool
    model: dict[str, Any] | None = None
    error: str = ""


@record
class ExonerationChange(Payload):
    """Switch exoneration on or off; without ``on``, only ask."""

    on: bool | None = None


@record
class Exoneration(Payload):
    """Whether an OK topic observation means its topics are not abnormal (the thesis'
    model: off)."""

    on: bool


OBSERVER_LIST = Verb(observers_api("list"), Empty, ObserversReply, threaded=False)
OBSERVER_ADD = Verb(observers_api("add"), ObserverAdd, ObserverActive, threaded=False)
OBSERVER_CHANGE = Verb(observers_api("change"), ObserverChange, ObserverActive, threaded=False)
OBSERVER_REMOVE = Verb(observers_api("remove"), ObserverId, ObserverId, threaded=False)
OBSERVER_ACTIVATE = Verb(observers_api("activate"), ObserverId, ObserverActive, threaded=False)
OBSERVER_DEACTIVATE = Verb(observers_api("deactivate"), ObserverId, ObserverActive, threaded=False)
OBSERVER_LATEST = Verb(observers_api("latest"), Empty, LatestReply, threaded=False, timeout=5.0)
# only the executive and its services change the model; anyone with a login reads it
DIAGNOSIS_MODEL_CHANGE = Verb(DIAGNOSIS_MODEL, ModelChange, ModelReply, threaded=False)
DIAGNOSIS_MODEL_READ = Verb(DIAGNOSIS_MODEL + "/read", Empty, ModelReply, threaded=False)
DIAGNOSIS_EXONERATE = Verb(DIAGNOSIS_EXONERATION, ExonerationChange, Exoneration, timeout=10.0)
