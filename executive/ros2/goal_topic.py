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

Anything on the robot's DDS domain may publish there: every submission is hostile input.
Whatever it holds (not JSON, Infinity or NaN, nesting too deep, a megabyte, wrong types)
it gets one reply and nothing is stored unless it is a goal the ``goal/add`` verb takes.
At most :data:`WAITING` submissions wait; beyond that, and beyond :data:`RATE` a second
from one publisher (a DDS writer), a submission is dropped and answered ``busy``.
"""

from __future__ import annotations

import contextlib
import json
import logging
import queue
import threading
from collections.abc import Callable
from typing import Any

from executive.bus.api.planning import GOAL_ADD, GoalAdd
from executive.bus.schema import plain
from executive.bus.service import Context, Service
from executive.ros2.cdr import CdrError
from executive.ros2.link import Ros2Link
from executive.ros2.names import dds_topic
from executive.ros2.participant import Reader, Writer
from executive.ros2.qos import dds_qos
from knowledge.errors import DuraError, excerpt
from knowledge.ros2_spec import PROFILES, QosProfile

log = logging.getLogger("dura.ros2")

STRING = "std_msgs/msg/String"
ANSWER = 10.0  # seconds the high level gets to take a goal


WAITING = 100  # submissions that may wait for the high level; more are dropped
RATE = 10.0  # submissions a second one publisher may make (a burst of BURST)
BURST = 20
LONGEST = 64 * 1024  # characters of a submission, at most


def submission(text: str) -> GoalAdd:
    """Read one submission: a goal expression, or a JSON object with its options, checked
    as the ``goal/add`` verb checks a request.

    Raises:
        ValueError: not a goal's submission (the reason, quoting little of it).
    """
    if len(text) > LONGEST:
        raise ValueError(f"{len(text)} characters (at most {LONGEST})")
    stripped = text.strip()
    if not stripped.startswith("{"):
        return GoalAdd(stripped)
    try:
        data = json.loads(stripped, parse_constant=_no_constant)
    except RecursionError:
        raise ValueError("JSON nested too deeply") from None
    except json.JSONDecodeError as e:
        raise ValueError(f"not JSON ({e.msg} at character {e.pos})") from None
    if not isinstance(data, dict) or not isinstance(data.get("expression"), str):
        raise ValueError("a JSON submission needs an 'expression' (a string)")
    unknown = set(data) - {"expression", "priority", "deadline"}
    if unknown:
        name = excerpt(sorted(unknown)[0], 40)
        raise ValueError(f"unknown key '{name}' (expression, priority, deadline)")
    try:
        return GoalAdd.from_payload(data)
    except DuraError as e:
        raise ValueError(str(e)) from None


def _no_constant(name: str) -> Any:
    raise ValueError(f"{name} is not a number a goal takes")


class RateLimit:
    """A token bucket per publisher: ``rate`` a second, bursts of ``burst``."""

    def __init__(self, rate: float = RATE, burst: int = BURST) -> None:
        self.rate = rate
        self.burst = burst
        self._buckets: dict[int, tuple[float, float]] = {}  # publisher -> (tokens, when)

    def allows(self, publisher: int, now: float) -> bool:
        tokens, then = self._buckets.get(publisher, (float(self.burst), now))
        tokens = min(float(self.burst), tokens + (now - then) * self.rate)
        if len(self._buckets) > 1000:  # publishers come and go: forget the full buckets
            self._buckets = {p: b for p, b in self._buckets.items() if b[0] < self.burst}
        allowed = tokens >= 1.0
        self._buckets[publisher] = (tokens - 1.0 if allowed else tokens, now)
        return allowed


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
        self._queue: queue.Queue[bytes | None] = queue.Queue(WAITING)
        self._limit = RateLimit()
        self._dropped: dict[str, int] = {}  # how many were dropped, by reason: to answer
        self._lock = threading.Lock()
        self._thread: threading.Thread | None = None
        self._reader: Reader | None = None
        self._writer: Writer | None = None
        self._decode: Callable[[bytes], dict[str, Any]] = lambda data: {}

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
        # keep all: DDS itself drops nothing unanswered, what comes in is answered here
        every = dds_qos(QosProfile(history="keep_all"))
        self._reader = link.participant.reader(dds_topic(self.topic), string, every, self._arrived)
        link.discovery.declare(self._writer.guid, writer=True)
        link.discovery.declare(self._reader.guid, writer=False)
        self._decode = link.library.decoder(STRING)
        self._thread = threading.Thread(target=self._run, name="ros2-goals", daemon=True)
        self._thread.start()

    def on_deactivate(self) -> None:
        if self._thread is not None:
            with self._queue.mutex:  # make room for the end, whatever waits
                self._queue.queue.clear()
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
            if not info.valid_data:
                continue
            if not self._limit.allows(info.publication_handle, received):
                reason = f"busy: more than {RATE:g} goals a second from one publisher, dropped"
            else:
                try:
                    self._queue.put_nowait(bytes(data))
                    continue
                except queue.Full:
                    reason = f"busy: {WAITING} goals wait already, dropped"
            with self._lock:
                wake = not self._dropped
                self._dropped[reason] = self._dropped.get(reason, 0) + 1
            if wake:
                with contextlib.suppress(queue.Full):
                    self._queue.put_nowait(b"")  # the worker answers the dropped ones

    def _run(self) -> None:
        while (data := self._queue.get()) is not None:
            self._answer_dropped()
            if not data:
                continue
            try:
                self._reply(self._submit(data))
            except Exception as e:  # the thread must live on, whatever a submission holds
                log.exception("a goal from ROS 2 failed")
                self._reply({"accepted": False, "reason": f"internal error: {type(e).__name__}"})

    def _answer_dropped(self) -> None:
        with self._lock:
            dropped, self._dropped = self._dropped, {}
        for reason, count in dropped.items():
            for _ in range(count):
                self._reply({"accepted": False, "reason": reason})

    def _submit(self, data: bytes) -> dict[str, Any]:
        try:
            text = str(self._decode(data)["data"])
        except (CdrError, KeyError, ValueError, UnicodeDecodeError) as e:
            log.warning("ignored a malformed goal from ROS 2: %s", excerpt(str(e)))
            return {"accepted": False, "reason": f"not a std_msgs/msg/String: {excerpt(str(e))}"}
        try:
            request = submission(text)
        except (ValueError, TypeError) as e:
            reason = f"not a goal: {excerpt(str(e))}"
            return {"expression": excerpt(text), "accepted": False, "reason": reason}
        try:
            goal = GOAL_ADD.call(self.context.bus, request, timeout=ANSWER).goal
        except DuraError as e:
            log.info("goal from ROS 2 refused: %s", excerpt(str(e)))
            reason = excerpt(str(e))
            return {"expression": excerpt(request.expression), "accepted": False, "reason": reason}
        log.info("goal %s from ROS 2: %s", goal.id, excerpt(request.expression))
        return {"expression": request.expression, "accepted": True, "goal": plain(goal)}

    def _reply(self, reply: dict[str, Any]) -> None:
        if self._writer is None:
            return
        try:
            text = json.dumps(reply, default=str)
            self._writer.write(self.link.library.create(STRING, {"data": text}))
        except DuraError as e:
            log.warning("cannot answer a goal from ROS 2: %s", e)
