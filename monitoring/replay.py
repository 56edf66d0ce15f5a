"""Replay recorded messages through a robot's observers, diagnosis and repair rules,
with the recording's time as the clock: monitoring tuned on recorded data.

A :class:`Replay` is the monitoring part of the executive without threads, bus or wall
clock, single-threaded and deterministic. It takes bus messages (``topic/<name>``,
``resources``, ``component/<name>/state``, ...) in order of their reception time,
from wherever they come (a ROS 2 bag, a recording of a dura run, a test), and between
two messages runs everything that was due, as the executive's services would have:

- each observer of the robot description (ids ``<component>/<index>``, built as the
  observer manager builds them) observes while its component is ready: it starts
  afresh when its component becomes ready, reports first after its start-up time (at
  least one loop) and then once per loop, at the recording's times; messages reach
  it with the recording's reception (and, where it has them, send) times;
- the diagnosis engine learns its observers from their observations and keeps its
  nodes to the components that are ready; it diagnoses ``settle`` seconds after a
  verdict or the model changed and repeats a faulty result every ``period`` seconds,
  as the diagnosis service does;
- the repair rules are evaluated on every observation and every diagnosis, with the
  recording's time as their clock; an action that fires is reported
  (:class:`RepairEntry`: "would restart lidar"), never run.

An observer loops as the live observer manager did where the recording says when
(``loops``: the stamps of a dura run's recorded observations, per observer), else once
per period from its start: a replay of a live run then sees each silence at the loop
the live run saw it, diagnoses it at the same time, and before the recorded repair
that the live diagnosis caused (a restart stops the component a few ms later).

Times are integer nanoseconds since the epoch, as the recording has them, from the
messages through the observers' loops (:meth:`Observer.observe_ns`) to the timeline,
whose entries are seconds since ``origin``: seconds since the epoch as floats are 240 ns
apart, and a message exactly one timeout before a loop would not be seen as one.

A recording without component states (a ROS 2 bag) counts every component as ready
from the start. An observer that listens to a key the recording does not have is not
replayed (:attr:`Timeline.skipped` says why). A recording of a dura run also holds
what the live run diagnosed and repaired: that goes to :attr:`Timeline.recorded`.

A message that does not decode is counted per topic with its first reason
(:attr:`Timeline.undecodable`), never dropped silently: a recording's messages count
themselves when an observer fails to decode them (:mod:`executive.bags.message`), and
the replay counts the component states, diagnoses and events it cannot read. The
replay goes on without them.
"""

from __future__ import annotations

import bisect
import heapq
import logging
from collections.abc import Callable, Collection, Iterable, Mapping, Sequence
from dataclasses import dataclass

from executive.bus.keys import DIAGNOSES, EVENTS
from executive.bus.message import Message
from executive.bus.payloads import ComponentState
from executive.bus.states import Lifecycle
from executive.bus.undecodable import UndecodableMessages
from knowledge.description import RobotDescription
from knowledge.errors import BusError
from monitoring.diagnosis.diagnosis_service import PERIOD, SETTLE
from monitoring.diagnosis.engine import DiagnosisEngine
from monitoring.diagnosis.model import Node, UpdateAction
from monitoring.diagnosis.timed import TimedDiagnosis
from monitoring.observer import Environment, Handler, Observer, ObserverResult, make_observer
from monitoring.observer_config import config_of
from monitoring.repair.engine import RuleEngine
from monitoring.repair.rule import RuleSet, read_rules
from monitoring.timeline import (
    DiagnosisEntry,
    Entry,
    ObservationEntry,
    RepairEntry,
    StateEntry,
    Timeline,
    recorded_diagnosis,
    recorded_repair,
)

log = logging.getLogger("dura.replay")

STOPPED = (Lifecycle.STOPPING, Lifecycle.STOPPED, Lifecycle.EXITED, Lifecycle.FAILED)


def watched_topics(robot: RobotDescription) -> set[str]:
    """Return the topics the robot's observers listen to.

    Raises:
        ConfigError: an observer of the robot description is invalid.
    """
    found: set[str] = set()
    for component in robot.components.values():
        for spec in component.observers:
            observer = make_observer(config_of(spec, path=str(robot.path)))
            found.update(
                k.removeprefix("topic/") for k, _ in observer.inputs() if k.startswith("topic/")
            )
    return found


def state_component(key: str) -> str | None:
    """Return the component of a ``component/<name>/state`` key, else ``None``."""
    parts = key.split("/")
    return parts[1] if len(parts) == 3 and parts[0] == "component" and parts[2] == "state" else None


@dataclass
class _Slot:
    index: int
    id: str
    component: str
    observer: Observer
    inputs: list[tuple[str, Handler]]
    active: bool = False
    generation: int = 0  # due times of older generations are void


class Replay:
    """Monitoring of one robot, driven by recorded messages (see the module docstring).

    Args:
        robot: the robot description whose observers and rules to replay.
        provided: the keys the recording has messages on (``topic/scan``, ``resources``,
            ``component/lidar/state``).
        origin_ns: the recording's time of the timeline's 0 (its first message), in
            integer nanoseconds since the epoch, as every time the replay takes.
        start_ns: when to start observing (default: ``origin_ns``).
        rule_sets: the repair rules (default: the robot description's rules files).
        exonerate, max_card, timeout: the diagnosis engine's options (as live: off,
            none, 2 s).
        settle, period: the diagnosis service's timing (as live).
        on_entry: called with each timeline entry as it happens.
        loops: when each observer (by id) looped live, in the recording's time (ns), sorted.
        undecodable: where to count the messages that do not decode (the recording's
            own count, which its messages add to; default: a count of the replay's own).

    Raises:
        ConfigError, AspError: an observer or a rules file of the robot is invalid.
    """

    def __init__(
        self,
        robot: RobotDescription,
        *,
        provided: Collection[str],
        origin_ns: int,
        start_ns: int | None = None,
        rule_sets: Sequence[RuleSet] | None = None,
        exonerate: bool = False,
        max_card: int | None = None,
        timeout: float | None = 2.0,
        settle: float = SETTLE,
        period: float = PERIOD,
        on_entry: Callable[[Entry], None] | None = None,
        loops: Mapping[str, Sequence[int]] | None = None,
        undecodable: UndecodableMessages | None = None,
    ) -> None:
        self.robot = robot
        self.undecodable = UndecodableMessages() if undecodable is None else undecodable
        self._loops = dict(loops or {})
        self.origin_ns = origin_ns
        self.start_ns = origin_ns if start_ns is None else start_ns
        self.now_ns = self.start_ns
        self._on_entry = on_entry
        self._with_states = any(state_component(k) is not None for k in provided)
        self._states: dict[str, Lifecycle] = {}
        self._reasons: dict[str, str] = {}
        self._slots: list[_Slot] = []
        self._feeds: dict[str, tuple[Handler, ...]] = {}
        self._skipped: list[str] = []
        self._load_observers(set(provided))
        engine = DiagnosisEngine(exonerate=exonerate, max_card=max_card, timeout=timeout)
        self.diagnosis = TimedDiagnosis(engine, settle=settle, period=period)
        if rule_sets is None:
            rule_sets = [read_rules(path) for path in robot.rules]
        self.rules = RuleEngine(rule_sets, clock=lambda: self.now) if rule_sets else None
        self._due: list[tuple[int, int, int]] = []  # observer loops: (time, slot, generation)
        self._verdicts: dict[tuple[str, str, tuple[str, ...], tuple[str, ...]], object] = {}
        self._recorded_last: tuple[object, ...] | None = None
        self._begun = False
        self._entries: list[Entry] = []
        self._recorded: list[DiagnosisEntry | RepairEntry] = []
        self.messages = 0

    # --- set-up ---------------------------------------------------------------------

    def _load_observers(self, provided: set[str]) -> None:
        """Make the robot's observers as the observer manager does; keep those whose
        inputs the recording has."""
        robot = self.robot
        for component in robot.components.values():
            for i, spec in enumerate(component.observers):
                observer_id = f"{component.name}/{i}"
                environment = Environment(
                    owner=component.name,
                    behavior=component.name if component.name in robot.behaviors else None,
                    component_state=self._states.get,
                )
                where = f"{component.kind.value} '{component.name}'"
                config = config_of(spec, path=str(robot.path), owner=where)
                observer = make_observer(config, environment)
                inputs = observer.inputs()
                missing = sorted({key for key, _ in inputs if key not in provided})
                if missing:
                    names = ", ".join(k.removeprefix("topic/") for k in missing)
                    self._skipped.append(f"{observer_id} ({config.type}): no {names} recorded")
                    continue
                index = len(self._slots)
                self._slots.append(_Slot(index, observer_id, component.name, observer, inputs))

    @property
    def now(self) -> float:
        """The replay's clock, in seconds since the epoch (the rules' clock)."""
        return self.now_ns / 1e9

    @property
    def observers(self) -> list[str]:
        """The ids of the observers that are replayed."""
        return [slot.id for slot in self._slots]

    @property
    def loop(self) -> float:
        """The longest loop of the replayed observers (seconds): how far a replay may
        see something later or sooner than the live run."""
        return max((slot.observer.period for slot in self._slots), default=0.0)

    @property
    def skipped(self) -> list[str]:
        """The observers that are not replayed, each with the reason."""
        return list(self._skipped)

    @property
    def listened(self) -> set[str]:
        """The keys whose messages matter: the replayed observers' inputs, component
        states, and what the recording says was diagnosed and repaired."""
        return {key for slot in self._slots for key, _ in slot.inputs} | {DIAGNOSES, EVENTS}

    # --- input ----------------------------------------------------------------------

    def run(self, messages: Iterable[Message], end_ns: int | None = None) -> Timeline:
        """Replay messages (in order of reception), then up to ``end_ns`` (default: the
        last message), and return the timeline."""
        last = self.start_ns
        for message in messages:
            self.deliver(message)
            last = max(last, message.received_ns)
        return self.finish(last if end_ns is None else end_ns)

    def deliver(self, message: Message) -> None:
        """Run what was due until the message was received, then take it in."""
        t = message.received_ns
        name = state_component(message.key)
        if t < self.start_ns:
            if name is not None:  # before the window: only who is ready counts
                self._component_state(message, t, quiet=True)
            return
        self.advance(t)
        self.messages += 1
        if name is not None:
            self._component_state(message, self.now_ns)
        elif message.key == DIAGNOSES:
            self._recorded_diagnosis(message, self.now_ns)
        elif message.key == EVENTS:
            self._recorded_event(message, self.now_ns)
        for handler in self._feeds.get(message.key, ()):
            try:
                handler(message)
            except BusError:  # as the bus drops a malformed message; the recording counts it
                continue
            except Exception:
                log.exception("observer handler for %s failed", message.key)

    def advance(self, until_ns: int) -> None:
        """Run every observer loop and diagnosis that is due until ``until_ns``."""
        if not self._begun:
            if until_ns < self.start_ns:
                return
            self._begin()
        due = self._due
        diagnosis = self.diagnosis
        while True:  # the earliest of the next loop and the diagnosis' wake; loops first
            wake_ns = diagnosis.wake_at_ns
            if due and due[0][0] <= until_ns and (wake_ns is None or due[0][0] <= wake_ns):
                t, index, generation = heapq.heappop(due)
                self.now_ns = max(self.now_ns, t)
                slot = self._slots[index]
                if slot.active and slot.generation == generation:
                    self._loop(slot, t)
            elif wake_ns is not None and wake_ns <= until_ns:
                self.now_ns = max(self.now_ns, wake_ns)
                self._diagnosed(wake_ns)
            else:
                break
        self.now_ns = max(self.now_ns, until_ns)

    def finish(self, end_ns: int) -> Timeline:
        """Run what is due until ``end_ns`` and return the timeline of the whole replay."""
        end_ns = max(end_ns, self.start_ns)
        self.advance(end_ns)
        return Timeline(
            origin=self.origin_ns / 1e9,
            begin=self._time(self.start_ns),
            end=self._time(end_ns),
            entries=tuple(self._entries),
            recorded=tuple(self._recorded),
            messages=self.messages,
            skipped=tuple(self._skipped),
            undecodable=self.undecodable.topics(),
        )

    # --- components -----------------------------------------------------------------

    def _begin(self) -> None:
        self._begun = True
        self.now_ns = self.start_ns
        if not self._with_states:  # a bag of a robot without dura: everything runs
            for name in self.robot.components:
                self._states[name] = Lifecycle.READY
        ready = [n for n, state in self._states.items() if state is Lifecycle.READY]
        self._model(UpdateAction.ADD, ready, self.start_ns)
        for slot in self._slots:
            self._refresh(slot, self.start_ns)

    def _component_state(self, message: Message, t: int, *, quiet: bool = False) -> None:
        try:
            state = ComponentState.from_payload(message.payload)
        except BusError:  # its JSON: the recording counts it
            return
        except (KeyError, ValueError, TypeError) as e:
            self._unreadable(message, "component state", e)
            return
        name = state.component
        if name not in self.robot.components:
            return
        old = self._states.get(name)
        self._states[name] = state.state
        if quiet or old is state.state:
            return
        self._emit(StateEntry(self._time(t), name, state.state.value, state.reason))
        if state.state is Lifecycle.READY:
            self._model(UpdateAction.ADD, [name], t)
        elif state.state in STOPPED:
            self._model(UpdateAction.REMOVE, [name], t)
        for slot in self._slots:
            if slot.component == name:
                self._refresh(slot, t)

    def _model(self, action: UpdateAction, names: list[str], t: int) -> None:
        """Add or remove nodes as the task executor does when components start or stop."""
        specs = [self.robot.components[name] for name in names]
        nodes = [Node(c.name, tuple(c.subscribes), tuple(c.publishes)) for c in specs]
        self.diagnosis.change_model(action, nodes, t)

    def _refresh(self, slot: _Slot, t: int) -> None:
        """(De)activate an observer as its component's state says."""
        should = self._states.get(slot.component) is Lifecycle.READY
        if should == slot.active:
            return
        slot.active = should
        slot.generation += 1
        for key, handler in slot.inputs:
            handlers = self._feeds.get(key, ())
            if should:
                self._feeds[key] = (*handlers, handler)
            else:
                self._feeds[key] = tuple(h for h in handlers if h is not handler)
        if should:
            start_up = round(slot.observer.first_report * 1e9)
            first = t + start_up
            due = self._next_loop(slot, first - round(slot.observer.period * 0.5e9), first)
            # the live observer started start-up time before its first loop: the recorder
            # heard of the component's start a little after the live observers did
            slot.observer.start_ns(min(t, due - start_up))
            heapq.heappush(self._due, (due, slot.index, slot.generation))
        else:
            for old in [k for k in self._verdicts if k[0] == slot.id]:
                del self._verdicts[old]

    # --- observers ------------------------------------------------------------------

    def _next_loop(self, slot: _Slot, after: int, otherwise: int) -> int:
        """The first live loop of the observer after ``after``, if the recording says."""
        times = self._loops.get(slot.id)
        if not times:
            return otherwise
        i = bisect.bisect_right(times, after)
        return times[i] if i < len(times) else otherwise

    def _loop(self, slot: _Slot, t: int) -> None:
        due = self._next_loop(slot, t, t + round(slot.observer.period * 1e9))
        heapq.heappush(self._due, (due, slot.index, slot.generation))
        try:
            results = slot.observer.observe_ns(t)
        except Exception:
            log.exception("observer %s failed", slot.id)
            return
        for result in results:
            self._observed(slot, result, t)

    def _observed(self, slot: _Slot, result: ObserverResult, t: int) -> None:
        info = result.info
        key = (slot.id, info.type, info.resource, info.callerids)
        verdict = (info.observation, info.observation_msg)
        if self._verdicts.get(key) != verdict:
            self._verdicts[key] = verdict
            self._emit(ObservationEntry(self._time(t), slot.id, info, dict(result.values)))
        self.diagnosis.observe(info, t)
        if self.rules is not None:
            self.rules.observe(info)
            self._fire(self.rules, t)

    # --- diagnosis and rules ----------------------------------------------------------

    def _diagnosed(self, t: int) -> None:
        published = self.diagnosis.wake(t)
        if published is None:
            return
        result = published.result
        if published.changed:
            failed = tuple(str(o) for o in result.failed)
            self._emit(DiagnosisEntry(self._time(t), result.status.value, result.diagnoses, failed))
        if self.rules is not None:
            self.rules.diagnosed(result.to_info(t / 1e9))
            self._fire(self.rules, t)

    def _fire(self, rules: RuleEngine, t: int) -> None:
        for fired in rules.evaluate():
            action = fired.rule.action.describe()
            self._emit(RepairEntry(self._time(t), fired.rule.name, action, fired.firing.faulty))

    # --- what the recording says --------------------------------------------------------

    def _recorded_diagnosis(self, message: Message, t: int) -> None:
        try:
            entry = recorded_diagnosis(message.payload, self._time(t))
        except BusError:
            return
        except (KeyError, ValueError, TypeError) as e:
            self._unreadable(message, "diagnosis", e)
            return
        if (entry.status, entry.diagnoses) != self._recorded_last:
            self._recorded_last = (entry.status, entry.diagnoses)
            self._recorded.append(entry)

    def _recorded_event(self, message: Message, t: int) -> None:
        try:
            entry = recorded_repair(message.payload, self._time(t))
        except BusError:
            return
        except (KeyError, ValueError, TypeError, AttributeError) as e:
            self._unreadable(message, "event", e)
            return
        if entry is not None:
            self._recorded.append(entry)

    def _unreadable(self, message: Message, what: str, error: Exception) -> None:
        """Count a message whose JSON decoded but is not the payload its key carries."""
        self.undecodable.add(message.key, f"not a {what} ({type(error).__name__}: {error})")

    # --- output ---------------------------------------------------------------------

    def _time(self, t: int) -> float:
        """Seconds since the origin (to the microsecond, as the timeline has them)."""
        return round((t - self.origin_ns) / 1e9, 6)

    def _emit(self, entry: Entry) -> None:
        self._entries.append(entry)
        if self._on_entry is not None:
            self._on_entry(entry)
