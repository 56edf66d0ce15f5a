"""A small kit of ROS 2 nodes on plain Cyclone DDS, speaking ROS 2's wire conventions.

The stand-in nodes of the example use it in place of rclpy (which needs a ROS
installation): a :class:`Node` is one DDS participant that announces its node, with
its readers' and writers' gids, on ``ros_discovery_info`` as every ROS 2 process does;
topics are ``rt/<name>``; a service ``/x`` is ``rq/xRequest`` and ``rr/xReply`` with
rmw_cyclonedds' request header (``guid_``, ``seq_``) before the message; an
:class:`ActionServer` serves ``send_goal``, ``get_result`` and ``cancel_goal`` and
publishes ``feedback`` and ``status`` as rcl_action does; a :class:`LifecycleNode`
serves ``get_state`` and ``change_state`` and publishes ``transition_event`` with
rcl_lifecycle's states and transitions.

It shares no code with dura, so that dura's tests against these nodes check dura
against an independent rendering of the conventions.
"""

from __future__ import annotations

import json
import os
import threading
import time
import uuid
from collections.abc import Callable
from typing import Any

from cyclonedds.core import (
    Entity,
    InstanceState,
    Policy,
    Qos,
    ReadCondition,
    SampleState,
    ViewState,
    WaitSet,
)
from cyclonedds.domain import DomainParticipant
from cyclonedds.idl import IdlStruct
from cyclonedds.internal import DDS
from cyclonedds.pub import DataWriter
from cyclonedds.sub import DataReader
from cyclonedds.topic import Topic
from cyclonedds.util import duration

from . import interfaces as ros

FOREVER = duration(infinite=True)
ANY = SampleState.Any | ViewState.Any | InstanceState.Any
Handler = Callable[[Any], None]


def qos(
    *, reliable: bool = True, depth: int = 10, latched: bool = False, user_data: bytes = b""
) -> Qos:
    """Make the DDS QoS rmw_cyclonedds gives a ROS 2 endpoint."""
    policies = [
        Policy.History.KeepLast(depth),
        Policy.Reliability.Reliable(FOREVER) if reliable else Policy.Reliability.BestEffort,
        Policy.Durability.TransientLocal if latched else Policy.Durability.Volatile,
        Policy.WriterDataLifecycle(autodispose=False),
        Policy.DataRepresentation(use_cdrv0_representation=True),
    ]
    if user_data:
        policies.append(Policy.Userdata(data=user_data))
    return Qos(*policies)


def now() -> ros.Time:
    t = time.time()
    return ros.Time(sec=int(t), nanosec=int((t % 1) * 1e9))


def params() -> dict[str, Any]:
    """Read the parameters dura passes a program (``DURA_PARAMS``, JSON)."""
    try:
        value = json.loads(os.environ.get("DURA_PARAMS") or "{}")
    except ValueError:
        return {}
    return value if isinstance(value, dict) else {}


def _user_data(endpoint: Any, key: str) -> str | None:
    """Read ``key=value;`` from a discovered endpoint's user data."""
    if endpoint is None or Policy.Userdata not in endpoint.qos:
        return None
    for pair in bytes(endpoint.qos[Policy.Userdata].data).decode(errors="replace").split(";"):
        name, _, value = pair.partition("=")
        if name == key:
            return value
    return None


class Node:
    """One ROS 2 node in a participant of its own; callbacks run on its spin thread."""

    def __init__(self, name: str, namespace: str = "/", domain_id: int | None = None) -> None:
        domain = int(os.environ.get("ROS_DOMAIN_ID", "0")) if domain_id is None else domain_id
        self.name, self.namespace = name, namespace
        self.participant = DomainParticipant(domain, Qos(Policy.Userdata(data=b"enclave=/;")))
        self._made: list[Entity] = [self.participant]
        self._topics: dict[str, Topic[Any]] = {}
        self._readers: list[bytes] = []
        self._writers: list[bytes] = []
        self._handlers: dict[int, tuple[DataReader[Any], Callable[[Any, Any], None]]] = {}
        self._waitset = WaitSet(self.participant)
        self._stop = threading.Event()
        self._ids = 0
        self._info = DataWriter(self.participant, self._topic("ros_discovery_info",
                                ros.ParticipantEntitiesInfo), qos(depth=1, latched=True))  # fmt: skip
        self._made.append(self._info)
        self._thread = threading.Thread(target=self._spin, daemon=True, name=f"spin-{name}")

    @property
    def full_name(self) -> str:
        return f"{self.namespace.rstrip('/')}/{self.name}"

    def _topic(self, name: str, kind: type[IdlStruct]) -> Topic[Any]:
        if name not in self._topics:
            self._topics[name] = Topic(self.participant, name, kind)
            self._made.append(self._topics[name])
        return self._topics[name]

    def writer(self, dds_topic: str, kind: type[IdlStruct], with_qos: Qos) -> DataWriter[Any]:
        """Make a writer of a DDS topic that belongs to this node."""
        writer = DataWriter(self.participant, self._topic(dds_topic, kind), with_qos)
        self._made.append(writer)
        self._writers.append(writer.guid.bytes)
        return writer

    def reader(
        self,
        dds_topic: str,
        kind: type[IdlStruct],
        with_qos: Qos,
        handler: Callable[[Any, Any], None],
    ) -> DataReader[Any]:
        """Make a reader of a DDS topic; ``handler(sample, info)`` gets each sample."""
        reader = DataReader(self.participant, self._topic(dds_topic, kind), with_qos)
        condition = ReadCondition(reader, ANY)
        self._waitset.attach(condition)
        self._made += [reader, condition]
        self._readers.append(reader.guid.bytes)
        self._handlers[reader._ref] = (reader, handler)
        return reader

    def publisher(self, topic: str, kind: type[IdlStruct], **options: Any) -> DataWriter[Any]:
        return self.writer("rt" + topic, kind, qos(**options))

    def subscription(
        self, topic: str, kind: type[IdlStruct], handler: Handler, **options: Any
    ) -> None:
        self.reader("rt" + topic, kind, qos(**options), lambda sample, info: handler(sample))

    def service(
        self,
        name: str,
        request: type[IdlStruct],
        response: type[IdlStruct],
        handler: Callable[[Any], dict[str, Any]],
    ) -> None:
        """Serve ``name``: ``handler(request)`` returns the response's fields."""
        self._ids += 1
        serviceid = f"serviceid={self.participant.guid.bytes[:12].hex()}.{self._ids};".encode()
        replies = self.writer(f"rr{name}Reply", response, qos(user_data=serviceid))
        requests: DataReader[Any]

        def answer(sample: Any, info: Any) -> None:
            fields = handler(sample)
            writer = requests.get_matched_publication_data(info.publication_handle)
            _wait_for_client(replies, _user_data(writer, "clientid"))
            replies.write(response(guid_=sample.guid_, seq_=sample.seq_, **fields))

        requests = self.reader(f"rq{name}Request", request, qos(user_data=serviceid), answer)

    def announce(self) -> None:
        """Publish this node with its endpoints on ``ros_discovery_info``."""
        self._info.write(
            ros.ParticipantEntitiesInfo(
                gid=ros.Gid(data=list(self.participant.guid.bytes)),
                node_entities_info_seq=[
                    ros.NodeEntitiesInfo(
                        node_namespace=self.namespace,
                        node_name=self.name,
                        reader_gid_seq=[ros.Gid(data=list(g)) for g in self._readers],
                        writer_gid_seq=[ros.Gid(data=list(g)) for g in self._writers],
                    )
                ],
            )
        )

    def start(self) -> None:
        """Announce the node and spin (serve its readers) on a thread."""
        self.announce()
        self._thread.start()

    def _spin(self) -> None:
        while not self._stop.is_set():
            self._waitset.wait(duration(milliseconds=50))
            for reader, handler in list(self._handlers.values()):
                for sample in reader.take(N=64):
                    info = sample.sample_info
                    if info.valid_data:
                        handler(sample, info)

    def run_until_stopped(self) -> None:
        """Start, then wait for SIGTERM or SIGINT (what dura sends to stop a program)."""
        import signal

        for signum in (signal.SIGTERM, signal.SIGINT):
            signal.signal(signum, lambda *_: self._stop.set())
        self.start()
        while not self._stop.wait(0.2):
            pass
        self.close()

    def close(self) -> None:
        """Delete the participant and everything in it."""
        self._stop.set()
        if self._thread.is_alive() and self._thread is not threading.current_thread():
            self._thread.join()
        if not self._made:
            return
        for entity in self._made:
            Entity._entities.pop(entity._ref, None)  # deleted below, not by the collector
        DDS._dll_handle.dds_delete(self.participant._ref)
        self._made.clear()


def _wait_for_client(replies: DataWriter[Any], clientid: str | None, limit: float = 0.1) -> None:
    """Wait until the reply writer has matched the reader of the client (rmw_cyclonedds
    waits 100 ms for it); a client without an id is assumed to be there."""
    if clientid is None:
        return
    deadline = time.monotonic() + limit
    while time.monotonic() < deadline:
        for handle in replies.get_matched_subscriptions():
            if _user_data(replies.get_matched_subscription_data(handle), "clientid") == clientid:
                return
        time.sleep(0.01)


# --- actions -------------------------------------------------------------------------

ACCEPTED, EXECUTING, CANCELING, SUCCEEDED, CANCELED, ABORTED = 1, 2, 3, 4, 5, 6


class GoalHandle:
    """A goal an action server runs: its fields, cancellation and feedback."""

    def __init__(self, server: ActionServer, goal_id: bytes, goal: Any) -> None:
        self.server, self.goal_id, self.goal = server, goal_id, goal
        self.status = ACCEPTED
        self.cancel_requested = threading.Event()
        self.result: Any = None
        self.ended = threading.Event()

    def publish_feedback(self, feedback: Any) -> None:
        self.server.feedback.write(
            self.server.feedback_type(goal_id=ros.UUID(uuid=list(self.goal_id)), feedback=feedback)
        )


class ActionServer:
    """Serves one action as rcl_action does; ``execute(handle)`` returns (status, result)."""

    def __init__(
        self,
        node: Node,
        name: str,
        types: Any,  # a module-like namespace: Goal, Result, SendGoal_Request, ...
        *,
        accept: Callable[[Any], bool],
        execute: Callable[[GoalHandle], tuple[int, Any]],
    ) -> None:
        self.node, self.types, self.accept, self.execute = node, types, accept, execute
        self.goals: dict[bytes, GoalHandle] = {}
        self.waiting: dict[bytes, list[tuple[int, int]]] = {}  # result requests: (guid, seq)
        self.lock = threading.Lock()
        base = f"{name}/_action/"
        self.feedback_type = types.FeedbackMessage
        self.feedback = node.publisher(base + "feedback", types.FeedbackMessage)
        self.status = node.publisher(base + "status", ros.GoalStatusArray, depth=1, latched=True)
        self._results = node.writer(f"rr{base}get_resultReply", types.GetResult_Response, qos())
        node.service(
            base + "send_goal", types.SendGoal_Request, types.SendGoal_Response, self._send
        )
        node.service(
            base + "cancel_goal", ros.CancelGoal_Request, ros.CancelGoal_Response, self._cancel
        )
        node.reader(f"rq{base}get_resultRequest", types.GetResult_Request, qos(), self._get_result)

    def _send(self, request: Any) -> dict[str, Any]:
        goal_id = bytes(request.goal_id.uuid)
        if not self.accept(request.goal):
            return {"accepted": False, "stamp": now()}
        handle = GoalHandle(self, goal_id, request.goal)
        with self.lock:
            self.goals[goal_id] = handle
        threading.Thread(target=self._run, args=(handle,), daemon=True).start()
        return {"accepted": True, "stamp": now()}

    def _run(self, handle: GoalHandle) -> None:
        handle.status = EXECUTING
        self._publish_status()
        status, result = self.execute(handle)
        with self.lock:
            handle.status, handle.result = status, result
            waiting = self.waiting.pop(handle.goal_id, [])
        handle.ended.set()
        self._publish_status()
        for guid, seq in waiting:
            self._reply(guid, seq, handle)

    def _reply(self, guid: int, seq: int, handle: GoalHandle | None) -> None:
        status = handle.status if handle is not None else 0
        result = (
            handle.result
            if handle is not None and handle.result is not None
            else self.types.Result()
        )
        self._results.write(
            self.types.GetResult_Response(guid_=guid, seq_=seq, status=status, result=result)
        )

    def _get_result(self, request: Any, info: Any) -> None:
        goal_id = bytes(request.goal_id.uuid)
        with self.lock:
            handle = self.goals.get(goal_id)
            if handle is not None and not handle.ended.is_set():
                self.waiting.setdefault(goal_id, []).append((request.guid_, request.seq_))
                return
        self._reply(request.guid_, request.seq_, handle)  # unknown goal: status UNKNOWN

    def _cancel(self, request: Any) -> dict[str, Any]:
        goal_id = bytes(request.goal_info.goal_id.uuid)
        with self.lock:
            handle = self.goals.get(goal_id)
        if handle is None:
            return {"return_code": 2}  # unknown goal id
        if handle.ended.is_set():
            return {"return_code": 3}  # terminated
        handle.status = CANCELING
        handle.cancel_requested.set()
        self._publish_status()
        info = ros.GoalInfo(goal_id=ros.UUID(uuid=list(goal_id)), stamp=now())
        return {"return_code": 0, "goals_canceling": [info]}

    def _publish_status(self) -> None:
        with self.lock:
            statuses = [
                ros.GoalStatus(
                    goal_info=ros.GoalInfo(goal_id=ros.UUID(uuid=list(g))), status=h.status
                )
                for g, h in self.goals.items()
            ]
        self.status.write(ros.GoalStatusArray(status_list=statuses))


# --- lifecycle nodes -------------------------------------------------------------------

PRIMARY = {1: "unconfigured", 2: "inactive", 3: "active", 4: "finalized"}
# transition id: (label, start state, intermediate state, goal state, callback name)
TRANSITIONS = {
    1: ("configure", 1, 10, 2, "on_configure"),
    2: ("cleanup", 2, 11, 1, "on_cleanup"),
    3: ("activate", 2, 13, 3, "on_activate"),
    4: ("deactivate", 3, 14, 2, "on_deactivate"),
    5: ("shutdown", 1, 12, 4, "on_shutdown"),
    6: ("shutdown", 2, 12, 4, "on_shutdown"),
    7: ("shutdown", 3, 12, 4, "on_shutdown"),
}
LABELS = {1: "unconfigured", 2: "inactive", 3: "active", 4: "finalized", 10: "configuring",
          11: "cleaningup", 12: "shuttingdown", 13: "activating", 14: "deactivating"}  # fmt: skip


class LifecycleNode(Node):
    """A managed node: override ``on_configure`` ... ``on_shutdown`` (return success)."""

    def __init__(self, name: str, namespace: str = "/", domain_id: int | None = None) -> None:
        super().__init__(name, namespace, domain_id)
        self.state = 1
        self._changing = threading.Lock()
        base = self.full_name
        self._events = self.publisher(base + "/transition_event", ros.TransitionEvent)
        self.service(base + "/get_state", ros.GetState_Request, ros.GetState_Response, self._get)
        self.service(
            base + "/change_state", ros.ChangeState_Request, ros.ChangeState_Response, self._change
        )

    def on_configure(self) -> bool:
        return True

    def on_activate(self) -> bool:
        return True

    def on_deactivate(self) -> bool:
        return True

    def on_cleanup(self) -> bool:
        return True

    def on_shutdown(self) -> bool:
        return True

    @property
    def active(self) -> bool:
        return self.state == 3

    def _get(self, request: Any) -> dict[str, Any]:
        return {"current_state": ros.State(id=self.state, label=LABELS[self.state])}

    def _event(self, label: str, tid: int, start: int, goal: int) -> None:
        self._events.write(ros.TransitionEvent(
            timestamp=time.time_ns(), transition=ros.Transition(id=tid, label=label),
            start_state=ros.State(id=start, label=LABELS[start]),
            goal_state=ros.State(id=goal, label=LABELS[goal]),
        ))  # fmt: skip

    def _change(self, request: Any) -> dict[str, Any]:
        with self._changing:
            found = TRANSITIONS.get(request.transition.id)
            if found is None or found[1] != self.state:
                return {"success": False}  # not a transition from this state
            label, start, middle, goal, callback = found
            self.state = middle
            self._event(label, request.transition.id, start, middle)
            ok = bool(getattr(self, callback)())
            self.state = goal if ok else start
            self._event("transition_success" if ok else "transition_failure",
                        97 if ok else 98, middle, self.state)  # fmt: skip
            return {"success": ok}


def action_types(module: Any, prefix: str) -> Any:
    """Collect an action's types from a module by prefix: ``NavigateToPose_Goal`` ..."""

    class Types:
        pass

    for part in ("Goal", "Result", "Feedback", "SendGoal_Request", "SendGoal_Response",
                 "GetResult_Request", "GetResult_Response", "FeedbackMessage"):  # fmt: skip
        setattr(Types, part, getattr(module, f"{prefix}_{part}"))
    return Types


def goal_uuid() -> bytes:
    return uuid.uuid4().bytes
