"""dura's state out to ROS 2: observations and diagnoses on ``/diagnostics``, events on
``/dura/events``, so that ROS tools (rqt_robot_monitor, the diagnostic aggregator,
``ros2 topic echo``) show what dura sees.

Each observation (bus key ``observations``) is one ``diagnostic_msgs/DiagnosticStatus``
named ``<node>: <type> <resources> [<caller ids>]``: level OK if the observation is
not a fault (number >= 0), ERROR if it is; message the observation's; hardware id the
observer's id; values the measured values, the number and the long message. The newest
diagnosis (bus key ``diagnoses``) is the status ``<node>: diagnosis``: OK for the
all-clear, ERROR when faults are diagnosed (message: the faulty components of the
smallest diagnosis), WARN when the diagnosis is inconsistent or timed out; each
diagnosis is a value. Statuses are sent batched, as one ``DiagnosticArray`` of those
that changed, at most every ``interval`` seconds (the observers report every loop, so
a status is refreshed while it holds).

Each executive event (bus key ``events``) is a ``std_msgs/String`` whose ``data`` is
the event's JSON, exactly as on dura's bus: ``{"id", "stamp", "kind", "subject",
"data"}``.
"""

from __future__ import annotations

import logging
import threading
import time
from collections.abc import Callable
from typing import Any

from executive.bus.keys import DIAGNOSES, EVENTS, OBSERVATIONS
from executive.bus.message import Message
from executive.bus.payloads import DiagnosisInfo, ObservationInfo
from executive.bus.service import Context, Service
from executive.ros2.link import Ros2Link
from executive.ros2.names import dds_topic
from executive.ros2.participant import Writer
from executive.ros2.qos import dds_qos
from knowledge.errors import DuraError
from knowledge.ros2_spec import PROFILES, Ros2Spec

log = logging.getLogger("dura.ros2")

DIAGNOSTIC_ARRAY = "diagnostic_msgs/msg/DiagnosticArray"
STRING = "std_msgs/msg/String"
OK, WARN, ERROR = 0, 1, 2  # diagnostic_msgs/msg/DiagnosticStatus levels


def observation_status(payload: dict[str, Any], node: str) -> dict[str, Any]:
    """Turn an ``observations`` payload into DiagnosticStatus fields."""
    info = ObservationInfo.from_payload(payload)
    callers = f" [{', '.join(info.callerids)}]" if info.callerids else ""
    values = {str(k): _text(v) for k, v in dict(payload.get("values") or {}).items()}
    values["observation"] = str(info.observation)
    if info.verbose_observation_msg:
        values["detail"] = info.verbose_observation_msg
    return {
        "level": ERROR if info.failed else OK,
        "name": f"{node}: {info.type} {' '.join(info.resource)}{callers}",
        "message": info.observation_msg,
        "hardware_id": str(payload.get("observer") or ""),
        "values": [{"key": k, "value": v} for k, v in values.items()],
    }


def diagnosis_status(payload: dict[str, Any], node: str) -> dict[str, Any]:
    """Turn a ``diagnoses`` payload into DiagnosticStatus fields."""
    info = DiagnosisInfo.from_payload(payload)
    level = {"OK": OK, "DIAGNOSED": ERROR}.get(info.status, WARN)
    if info.diagnoses:
        message = "faulty: " + ", ".join(info.diagnoses[0])
        if len(info.diagnoses) > 1:
            message += f" (or {len(info.diagnoses) - 1} other diagnoses)"
    else:
        message = info.status.lower()
    values = [{"key": "status", "value": info.status}]
    values += [
        {"key": f"diagnosis {i}", "value": ", ".join(d)}
        for i, d in enumerate(info.diagnoses, start=1)
    ]
    values.append({"key": "failed observers", "value": str(len(info.failed))})
    return {
        "level": level,
        "name": f"{node}: diagnosis",
        "message": message,
        "hardware_id": node,
        "values": values,
    }


def _text(value: Any) -> str:
    return f"{value:.6g}" if isinstance(value, float) else str(value)


class Ros2StatePublisher(Service):
    """Publish dura's observations, diagnoses and events to the robot's ROS 2 graph.

    Args:
        context: the executive's services' context (its bus).
        spec: the robot's ``ros2:`` section (topics ``diagnostics`` and ``events``).
        link: the executive's ROS 2 link; without one, the service opens its own.
        interval: seconds between two DiagnosticArrays at most.
    """

    name = "ros2-state"

    def __init__(
        self,
        context: Context,
        spec: Ros2Spec,
        *,
        link: Ros2Link | None = None,
        interval: float = 0.5,
    ) -> None:
        super().__init__(context)
        self.spec = spec
        self.interval = interval
        self._link = link
        self._own_link: Ros2Link | None = None
        self._pending: dict[str, dict[str, Any]] = {}
        self._changed = threading.Condition()
        self._stopping = False
        self._thread: threading.Thread | None = None
        self._writers: list[Writer] = []
        self._diagnostics: Writer | None = None
        self._events: Writer | None = None
        self._subscriptions: list[Any] = []
        self._node = ""  # dura's node in the ROS 2 graph, once configured

    def on_configure(self) -> None:
        """Open the writers (and a link if none was given).

        Raises:
            BusError: DDS refused a writer or the participant.
            ConfigError: the ``ros2:`` section cannot be used (its own link only).
        """
        link = self._link
        if link is None:
            link = self._own_link = Ros2Link(self.spec)
        qos = dds_qos(PROFILES["default"])
        if self.spec.diagnostics is not None:
            self._diagnostics = link.participant.writer(
                dds_topic(self.spec.diagnostics), link.library.idl(DIAGNOSTIC_ARRAY), qos
            )
            self._writers.append(self._diagnostics)
        if self.spec.events is not None:
            self._events = link.participant.writer(
                dds_topic(self.spec.events), link.library.idl(STRING), qos
            )
            self._writers.append(self._events)
        for writer in self._writers:
            link.discovery.declare(writer.guid, writer=True)
        self._node = link.discovery.node.strip("/")

    def on_activate(self) -> None:
        """Listen to the bus."""
        node = self._node
        bus = self.context.bus
        with self._changed:
            self._stopping = False
        if self._diagnostics is not None:
            self._subscriptions += [
                bus.subscribe(OBSERVATIONS, lambda m: self._status(m, observation_status, node)),
                bus.subscribe(DIAGNOSES, lambda m: self._status(m, diagnosis_status, node)),
            ]
            self._thread = threading.Thread(target=self._run, name="ros2-state", daemon=True)
            self._thread.start()
        if self._events is not None:
            self._subscriptions.append(bus.subscribe(EVENTS, self._event, decoded=False))

    def on_deactivate(self) -> None:
        for subscription in self._subscriptions:
            try:
                subscription.undeclare()
            except Exception as e:  # already closed with the bus
                log.debug("undeclare: %s", e)
        self._subscriptions.clear()
        with self._changed:
            self._stopping = True
            self._changed.notify_all()
        if self._thread is not None:
            self._thread.join()
            self._thread = None

    def on_shutdown(self) -> None:
        link = self._own_link or self._link
        for writer in self._writers:
            if link is not None and not link.participant.closed:
                link.discovery.retract(writer.guid)
            writer.close()
        self._writers.clear()
        self._diagnostics = self._events = None
        if self._own_link is not None:
            self._own_link.close()
            self._own_link = None

    # --- from the bus ---------------------------------------------------------------

    def _status(
        self, message: Message, convert: Callable[[dict[str, Any], str], dict[str, Any]], node: str
    ) -> None:
        try:
            status = convert(message.payload, node)
        except (KeyError, ValueError, TypeError) as e:
            log.warning("cannot show a malformed %s payload on ROS 2: %s", message.key, e)
            return
        with self._changed:
            self._pending[status["name"]] = status
            self._changed.notify_all()

    def _event(self, message: Message) -> None:
        link = self._own_link or self._link
        if self._events is None or link is None:
            return
        try:
            text = message.raw.decode()
            self._events.write(link.library.create(STRING, {"data": text}))
        except (UnicodeDecodeError, DuraError) as e:
            log.warning("cannot publish an event on ROS 2: %s", e)

    # --- the batching thread --------------------------------------------------------

    def _run(self) -> None:
        while True:
            with self._changed:
                while not self._pending and not self._stopping:
                    self._changed.wait()
                if self._stopping:
                    return
                batch = list(self._pending.values())
                self._pending.clear()
            self._publish(batch)
            with self._changed:
                self._changed.wait_for(lambda: self._stopping, self.interval)

    def _publish(self, statuses: list[dict[str, Any]]) -> None:
        link = self._own_link or self._link
        if self._diagnostics is None or link is None:
            return
        now = time.time()
        stamp = {"sec": int(now), "nanosec": int((now % 1) * 1e9)}
        try:
            self._diagnostics.write(
                link.library.create(
                    DIAGNOSTIC_ARRAY, {"header": {"stamp": stamp}, "status": statuses}
                )
            )
        except DuraError as e:
            log.warning("cannot publish diagnostics on ROS 2: %s", e)
