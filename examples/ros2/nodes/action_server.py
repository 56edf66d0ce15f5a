"""An action server as rcl_action serves one: ``send_goal``, ``get_result`` (held until
the goal ends), ``cancel_goal``, and the ``feedback`` and ``status`` topics."""

from __future__ import annotations

import threading
from collections.abc import Callable
from typing import Any

from . import interfaces as ros
from .rosnode import Node, now, qos

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


def action_types(module: Any, prefix: str) -> Any:
    """Collect an action's types from a module by prefix: ``NavigateToPose_Goal`` ..."""

    class Types:
        pass

    for part in ("Goal", "Result", "Feedback", "SendGoal_Request", "SendGoal_Response",
                 "GetResult_Request", "GetResult_Response", "FeedbackMessage"):  # fmt: skip
        setattr(Types, part, getattr(module, f"{prefix}_{part}"))
    return Types
