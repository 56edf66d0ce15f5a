"""Key expressions of the bus, relative to ``dura/<robot>/``, and the environment of a
component process.

A service that owns a key documents its payload in :mod:`executive.bus.payloads` (data
it publishes) or declares it in :mod:`executive.bus.api` (requests it serves), so that
each service can run in its own process, or on another machine, and still understand
the others.
"""

from __future__ import annotations

import re
from collections.abc import Callable

OBSERVATIONS = "observations"  # observation infos from observers
DIAGNOSES = "diagnoses"  # diagnosis results (diagnosis engine)
RESOURCES = "resources"  # resource monitor node infos
EXECUTIVE_ALIVE = "alive/executive"  # liveliness token of the executive process
EVENTS = "events"  # every KB event, as it is logged


TOPICS = "topic/"  # the keys of topic data, as publishers and subscribers name them
SENT = "from/"  # where topic data travels: ``from/<sender>/topic/<name>``
_WILD = re.compile(r"[*$]")


def wire_key(key: str, sender: str) -> str:
    """The key a message on ``key`` travels on when ``sender`` publishes it: the
    sender's name is part of the key of topic data, where access control checks it."""
    return f"{SENT}{sender}/{key}" if key.startswith(TOPICS) else key


def listened_key(key: str, *, component: bool = True) -> str:
    """The key a subscriber of ``key`` listens on: every sender of topic data.

    A component listens on ``from/*/topic/...``; every other session (the executive's,
    a service's, the CLI's) on ``from/**/topic/...``, which also matches keys of other
    topics (see :func:`heard`). The two never share a key expression: Zenoh's router
    keeps a closed session's state for as long as another session subscribes the very
    wildcard key expression it subscribed (or one under it; Zenoh 1.10), so a component that
    shared the executive's would leave its state there at every start."""
    if not key.startswith(TOPICS):
        return key
    return f"{SENT}{'*' if component else '**'}/{key}"


def heard(key: str) -> Callable[[str], bool] | None:
    """For a subscription of ``key`` on ``from/**/``, whether a message's key (as
    published, see :func:`sender_of`) is one of ``key``'s; ``None`` if any is.

    ``**`` may take chunks of the topic's name for the sender's: a topic ``a/topic/b``
    of sender ``s`` matches ``from/**/topic/b``, and its key (``topic/a/topic/b``) is
    not ``topic/b``."""
    if not key.startswith(TOPICS):
        return None
    if not _WILD.search(key):
        return key.__eq__
    import zenoh  # here: a component's environment reads these keys without the bus

    pattern = zenoh.KeyExpr(key)
    return lambda published: bool(pattern.includes(published))  # no KeyExpr per message


def sender_of(key: str) -> tuple[str, str]:
    """``(key as published, sender)`` of a key as it travels; ``(key, "")`` for a key
    that names no sender (the caller id then is the attachment's)."""
    if key.startswith(SENT):
        sender, _, rest = key[len(SENT) :].partition("/")
        return rest, sender
    return key, ""


def topic(name: str) -> str:
    """Component data on a named topic."""
    return f"topic/{name.strip('/')}"


def component(name: str, leaf: str) -> str:
    """``component/<name>/<leaf>``; leaves: cmd, state, result, feedback."""
    return f"component/{name}/{leaf}"


def api(verb: str) -> str:
    """A request the CLI (or another service) makes of the executive."""
    return f"executive/api/{verb}"


def component_alive(name: str, instance: str = "*") -> str:
    """The liveliness token a component process declares once it takes commands."""
    return f"alive/component/{name}/{instance}"


def host(name: str, leaf: str) -> str:
    """``host/<name>/<leaf>``: a host agent's requests (spawn, signal, logs) and the
    exits of its processes (exit)."""
    return f"host/{name}/{leaf}"


def host_alive(name: str = "*") -> str:
    """The liveliness token of a host agent that serves the executive."""
    return f"alive/host/{name}"


def service_alive(group: str = "*") -> str:
    """The liveliness token of a group of the executive's services (``tasks``,
    ``monitoring``, ``planning``), declared by the process that runs it."""
    return f"alive/service/{group}"


# The environment of every component process, set by the launcher and read by the SDK.
ENV_ROBOT = "DURA_ROBOT"  # the robot's name
ENV_COMPONENT = "DURA_COMPONENT"  # the component's name
ENV_ENDPOINT = "DURA_ENDPOINT"  # where the executive's bus listens
ENV_KIND = "DURA_KIND"  # "functionality" or "behavior"
ENV_INSTANCE = "DURA_INSTANCE"  # unique per started process; names its liveliness token


def observers_api(verb: str) -> str:
    """A request the observer manager serves: ``monitoring/observers/<verb>``.

    Requests and replies (errors are error replies with the reason):

    - ``list`` ``{}`` -> ``{"observers": [{"id", "type", "component", "enabled", "active",
      "main_loop_rate", "start_up_time"}]}``
    - ``add`` ``{"config": {observer entry}, "component": str | null, "name": str | null}``
      -> ``{"id", "active"}``
    - ``change`` ``{"id", "config"}`` -> ``{"id", "active"}`` (fresh state, same id)
    - ``remove`` ``{"id"}`` -> ``{"id"}``
    - ``activate`` / ``deactivate`` ``{"id"}`` -> ``{"id", "active"}``: an activated
      observer observes while its component is READY (always, if it has none)
    - ``latest`` ``{}`` -> ``{"observations": [payloads as on ``observations``]}``: the
      last observation of every resource of every active observer

    Each payload on ``observations`` is :class:`ObservationInfo` plus ``values`` (the
    measured values by name, e.g. ``{"frequency": 9.98}``) and ``observer`` (its id).
    """
    return f"monitoring/observers/{verb}"


# Model updates of the diagnosis engine (request/reply). Request:
#   {"action": "ADD" | "REMOVE" | "UPDATE" | "SET" | "GET",
#    "nodes": [{"name", "sub_topic": [...], "pub_topic": [...]}],
#    "observers": [{"type", "resource": [...], "callerids": [...]}]}
# ADD adds nodes and observers; REMOVE removes the named nodes and the given observers;
# UPDATE replaces the named nodes (they must exist) and adds the given observers; SET
# replaces the whole model; GET changes nothing. Reply: {"ok": true, "model": {...}} or
# {"ok": false, "error": "<reason>"}; a refused update leaves the model as it was.
DIAGNOSIS_MODEL = "diagnosis/model"

# Exoneration of the diagnosis engine at run time (request/reply): {"on": true | false}
# switches it (an OK topic observation then clears its topics), {} only asks; the reply
# is {"on": ...}, the setting now.
DIAGNOSIS_EXONERATION = "diagnosis/exonerate"
