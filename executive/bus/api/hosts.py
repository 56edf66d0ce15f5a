"""A host agent's API (``dura host``): the executive's launcher starts, signals and reads
the logs of component processes on another computer through it.

Each host serves its verbs under its own key, ``host/<name>/...``, so they are made per
host by the functions below (declared here once, as the other verbs are). Only the
executive (and its services) may call them: the bus's access control lets no operator
or component near a host's keys. The agent publishes the end of each process it
started on ``host/<name>/exit`` (:class:`ProcessExit`), stamped with its own clock; the
executive records the state with its own.
"""

from __future__ import annotations

from executive.bus.api.components import LogQuery, LogReply
from executive.bus.keys import host
from executive.bus.schema import Payload, Text
from executive.bus.verb import Empty, Verb
from knowledge.record_class import record

SPAWN_TIMEOUT = 10.0  # seconds: a fork, and a look for the program's pid
SIGNAL_TIMEOUT = 2.0


@record
class Spawn(Payload):
    """Start a component placed on the host under its supervisor. ``instance`` names the
    process's liveliness token; ``user`` and ``password`` are the component's own bus
    login (the host has none of its own to give); ``run`` marks the process tree."""

    component: Text
    instance: Text
    run: str | None = None
    user: str | None = None
    password: str | None = None


@record
class Spawned(Payload):
    """The started process: its supervisor's pid, the program's (once forked), and where
    its log is on the host."""

    pid: int
    log: str
    program: int | None = None


@record
class ProcessSignal(Payload):
    """A signal to a process the host started: to its whole process group, or only to
    its supervisor."""

    instance: Text
    signal: int
    group: bool = True


@record
class ProcessExit(Payload):
    """The payload of ``host/<name>/exit``: a process the host started has ended and was
    reaped (its exit code, or the signal that killed it)."""

    component: Text
    instance: Text
    pid: int
    exit_code: int | None = None
    signal: int | None = None
    stamp: float = 0.0
    output: tuple[Text, ...] = ()  # what it said last: the end of its traceback


def spawn(name: str) -> Verb[Spawn, Spawned]:
    return Verb(host(name, "spawn"), Spawn, Spawned, timeout=SPAWN_TIMEOUT)


def signal(name: str) -> Verb[ProcessSignal, Empty]:
    return Verb(host(name, "signal"), ProcessSignal, Empty, timeout=SIGNAL_TIMEOUT, threaded=False)


def logs(name: str) -> Verb[LogQuery, LogReply]:
    return Verb(host(name, "logs"), LogQuery, LogReply, timeout=5.0, threaded=False)


EXIT = "exit"  # the leaf of host/<name>/exit
STOPPING = "stopping"  # the leaf of host/<name>/stopping: the agent stops cleanly
