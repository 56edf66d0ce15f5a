"""Goals from ROS 2: a topic where ROS 2 tools submit goals to dura.

A ``std_msgs/msg/String`` on the ``ros2:`` section's ``goals`` topic (default
``/dura/goals``) is one goal: its ``data`` is the goal expression, or a JSON object
``{"expression": ..., "priority": 2, "deadline": 60}``. It goes through the
executive's ``goal/add`` verb, the same validation as ``dura goal add``::

    ros2 topic pub --once /dura/goals std_msgs/msg/String "{data: '(visited lab)'}"

Each submission's outcome is a ``std_msgs/msg/String`` on ``<goals>/replies``
(``/dura/goals/replies``), as JSON: ``{"expression", "accepted": true, "goal": {...}}``
or ``{"expression", "accepted": false, "reason": "..."}``; an accepted goal is also the
event GOAL_ADDED on ``/dura/events``. Submissions are handled one at a time, in order,
on a thread of their own (never on DDS's receive thread).
"""

from __future__ import annotations

import json
import logging
import queue
import threading
from typing import Any

from executive.bus.api.planning import GOAL_ADD, GoalAdd
from executive.bus.schema import plain
from executive.bus.service import Context, Service
from executive.ros2.cdr import CdrError
from executive.ros2.link import Ros2Link
from executive.ros2.names import dds_topic
from executive.ros2.participant import Reader, Writer
from executive.ros2.qos import dds_qos
from knowledge.errors import DuraError
from knowledge.ros2_spec import PROFILES

log = logging.getLogger("dura.ros2")

STRING = "std_msgs/msg/String"
ANSWER = 10.0  # seconds the high level gets to take a goal


def submission(text: str) -> GoalAdd:
    """Read one submission: a goal expression, or a JSON object with its options.

    Raises:
        ValueError: JSON that is not a goal's.
    """
    stripped = text.strip()
    if not stripped.startswith("{"):
        return GoalAdd(stripped)
    data = json.loads(stripped)
    if not isinstance(data, dict) or not isinstance(data.get("expression"), str):
        raise ValueError("a JSON submission needs an 'expression' (a string)")
    unknown = set(data) - {"expression", "priority", "deadline"}
    if unknown:
        raise ValueError(f"unknown key '{sorted(unknown)[0]}' (expression, priority, deadline)")
    return GoalAdd(data["expression"], int(data.get("priority", 0)), data.get("deadline"))


def replies_topic(goals: str) -> str:
    """Name the topic of the replies to the submissions on ``goals``."""
    return goals.rstrip("/") + "/replies"


class Ros2Goals(Service):
    """Takes goals from ROS 2 and answers each on the replies topic.

    Args:
        context: the executive's bus (the planning API answers there).
        link: the executive's ROS 2 link (participant, types, graph).
    """

    name = "ros2-goals"

    def __init__(self, context: Context, link: Ros2Link) -> None:
        super().__init__(context)
        self.link = link
        self.topic = link.spec.goals
        self._queue: queue.SimpleQueue[bytes | None] = queue.SimpleQueue()
        self._thread: threading.Thread | None = None
        self._reader: Reader | None = None
        self._writer: Writer | None = None

    def on_activate(self) -> None:
        """Read the goals topic and open the replies (nothing if ``goals`` is null).

        Raises:
            BusError: DDS refused the reader or the writer.
        """
        if self.topic is None:
            return
        link = self.link
        string = link.library.idl(STRING)
        qos = dds_qos(PROFILES["default"])
        self._writer = link.participant.writer(dds_topic(replies_topic(self.topic)), string, qos)
        self._reader = link.participant.reader(dds_topic(self.topic), string, qos, self._arrived)
        link.discovery.declare(self._writer.guid, writer=True)
        link.discovery.declare(self._reader.guid, writer=False)
        self._thread = threading.Thread(target=self._run, name="ros2-goals", daemon=True)
        self._thread.start()

    def on_deactivate(self) -> None:
        if self._thread is not None:
            self._queue.put(None)
            self._thread.join()
            self._thread = None
        for endpoint in (self._reader, self._writer):
            if endpoint is None:
                continue
            if not self.link.participant.closed:
                self.link.discovery.retract(endpoint.guid)
            endpoint.close()
        self._reader = self._writer = None

    def _arrived(self, samples: list[Any], received: float) -> None:
        for data, info in samples:
            if info.valid_data:
                self._queue.put(bytes(data))

    def _run(self) -> None:
        decode = self.link.library.decoder(STRING)
        while (data := self._queue.get()) is not None:
            try:
                text = str(decode(data)["data"])
            except CdrError as e:
                log.warning("ignored a malformed goal from ROS 2: %s", e)
                continue
            self._reply(self._submit(text))

    def _submit(self, text: str) -> dict[str, Any]:
        try:
            request = submission(text)
        except (ValueError, TypeError) as e:
            return {"expression": text, "accepted": False, "reason": f"not a goal: {e}"}
        try:
            goal = GOAL_ADD.call(self.context.bus, request, timeout=ANSWER).goal
        except DuraError as e:
            log.info("goal from ROS 2 refused: %s", e)
            return {"expression": request.expression, "accepted": False, "reason": str(e)}
        log.info("goal %s from ROS 2: %s", goal.id, request.expression)
        return {"expression": request.expression, "accepted": True, "goal": plain(goal)}

    def _reply(self, reply: dict[str, Any]) -> None:
        if self._writer is None:
            return
        try:
            text = json.dumps(reply, default=str)
            self._writer.write(self.link.library.create(STRING, {"data": text}))
        except DuraError as e:
            log.warning("cannot answer a goal from ROS 2: %s", e)
