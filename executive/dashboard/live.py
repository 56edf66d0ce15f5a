"""What the dashboard knows of a running robot, and the views the page shows of it.

:class:`LiveState` is plain data with no bus in it: the feed hands it the records of the
executive's replies and of its bus subscriptions, and asks it for views (JSON objects
the page renders, the pictures among them as SVG). One owner changes it: the
dashboard's event loop (see :mod:`executive.dashboard.feed`).
"""

from __future__ import annotations

import collections
import time
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from typing import Any

from executive.bus.api.components import lifecycle
from executive.bus.event_text import describe
from executive.bus.payloads import ComponentState, DiagnosisInfo
from executive.bus.reports import ComponentEntry, ExecutionStatus, ExecutorTask
from executive.bus.schema import plain
from executive.bus.states import Lifecycle
from executive.dashboard import gantt, graph, svg
from knowledge.description import FunctionalitySpec, RobotDescription
from knowledge.records import ComponentRecord, Event, Goal, Plan

OBSERVATION_HISTORY = 300.0  # seconds of measured values kept per observation (sparklines)
EVENTS_KEPT = 1000  # events the page can filter
PLAN_EVENTS_KEPT = 4000  # plan and step events kept for the Gantt chart

GOALS, PLAN, TASKS, FAULTS = "goals", "plan", "tasks", "faults"
QUERIES = (GOALS, PLAN, TASKS, FAULTS)  # what the feed asks the executive again
VIEWS = ("status", "goals", "plan", "components", "observations", "events")
_PLAN_KINDS = {"PLAN_START", "PLAN_STORED", "DISPATCH", "START", "END", "FAIL", "CANCEL",
               "REPLAN", "PLANNING"}  # fmt: skip
_FAULT_KINDS = {"FAULT", "PERMANENT_FAULT", "COMPONENT_RESET", "REPAIR"}


def stale(kind: str) -> set[str]:
    """What an event of ``kind`` makes out of date (the replies to ask again)."""
    if kind == "EXECUTIVE_STARTED":
        return set(QUERIES)
    found = set()
    if kind.startswith(("GOAL_", "INTEGRITY_")) or kind == "PLANNING":
        found.add(GOALS)
    if kind in _PLAN_KINDS or kind.startswith("GOAL_"):
        found.add(PLAN)
    if kind.startswith("TASK_") or kind == "CONFIGURATION":
        found.add(TASKS)
    if kind in _FAULT_KINDS:
        found |= {FAULTS, TASKS}
    return found


def component_state(lifecycle: ComponentState | None, *, permanent: bool, faulty: bool) -> str:
    """How a component is drawn: running, starting, paused, stopping, stopped, faulty
    (diagnosed, being repaired after a fault, or crashed) or permanently faulty."""
    if permanent:
        return "permanently faulty"
    if faulty:
        return "faulty"
    if lifecycle is None:
        return "stopped"
    phase = lifecycle.state
    if phase is Lifecycle.FAILED or (
        phase is Lifecycle.EXITED and (lifecycle.exit_code or lifecycle.signal)
    ):
        return "faulty"
    return {
        Lifecycle.READY: "running",
        Lifecycle.STARTING: "starting",
        Lifecycle.PAUSED: "paused",
        Lifecycle.STOPPING: "stopping",
    }.get(phase, "stopped")


@dataclass
class Track:
    """One observer's observations of one resource, with the recent measured values."""

    key: str
    latest: dict[str, Any]
    history: collections.deque[tuple[float, dict[str, float]]] = field(
        default_factory=collections.deque
    )

    def view(self) -> dict[str, Any]:
        return {**self.item(), "history": [[t, v] for t, v in self.history]}

    def item(self) -> dict[str, Any]:
        o = self.latest
        return {
            "key": self.key,
            "observer": o.get("observer", ""),
            "type": o.get("type", ""),
            "resource": list(o.get("resource") or []),
            "callerids": list(o.get("callerids") or []),
            "observation": o.get("observation"),
            "message": o.get("observation_msg", ""),
            "verbose": o.get("verbose_observation_msg", ""),
            "stamp": o.get("stamp", 0.0),
            "values": _numbers(o.get("values")),
        }


def event_item(event: Event) -> dict[str, Any]:
    """An event as the page shows it: its JSON form with its readable line (``text``)."""
    return {**plain(event), "text": describe(event)}


def _numbers(values: Any) -> dict[str, float]:
    if not isinstance(values, Mapping):
        return {}
    return {
        str(k): float(v)
        for k, v in values.items()
        if isinstance(v, int | float) and not isinstance(v, bool)
    }


class LiveState:
    """The robot as the page shows it (see the module docstring)."""

    def __init__(self, robot: RobotDescription, *, fleet: bool = False) -> None:
        self.robot = robot
        self.fleet = fleet  # a fleet's high level: its robots have the components
        self.layout = graph.layout(robot)
        self.goals: list[Goal] = []
        self.plan: Plan | None = None
        self.robots: list[str] | None = None  # a fleet's plan: the robot of each step
        self.execution = ExecutionStatus()
        self.tasks: list[ExecutorTask] = []
        self.lifecycles: dict[str, ComponentState] = {}
        self.faults: dict[str, ComponentRecord] = {}
        self.unusable: set[str] = set()
        self.diagnosis: DiagnosisInfo | None = None
        self.repairing: set[str] = set()
        self.tracks: dict[str, Track] = {}
        self.events: collections.deque[Event] = collections.deque(maxlen=EVENTS_KEPT)
        self.plan_events: collections.deque[Event] = collections.deque(maxlen=PLAN_EVENTS_KEPT)
        self._seen: set[int] = set()
        self.alive = False
        self.problem = ""

    # --- what the executive answered ---------------------------------------------------

    def set_goals(self, goals: list[Goal]) -> None:
        self.goals = goals

    def set_plan(
        self, plan: Plan | None, execution: ExecutionStatus, robots: list[str] | None = None
    ) -> None:
        self.plan, self.execution, self.robots = plan, execution, robots

    def set_tasks(self, tasks: list[ExecutorTask]) -> None:
        self.tasks = tasks

    def set_components(self, components: Iterable[ComponentEntry]) -> None:
        for c in components:
            self.lifecycles[c.component] = lifecycle(c)

    def set_faults(self, faults: Iterable[ComponentRecord], unusable: Iterable[str]) -> None:
        self.faults = {f.name: f for f in faults}
        self.unusable = set(unusable)

    def set_events(self, events: Iterable[Event]) -> None:
        """The event log's newest events, read when the feed starts (live ones may have
        come first: both are kept in the log's order)."""
        for event in events:
            self.add_event(event)
        for kept in (self.events, self.plan_events):
            ordered = sorted(kept, key=lambda e: e.id)
            kept.clear()
            kept.extend(ordered)

    # --- what the bus brought ----------------------------------------------------------

    def add_event(self, event: Event) -> bool:
        """Keep a logged event; returns whether it is new (the log and the live
        subscription may both bring it)."""
        number = event.id
        if number in self._seen:
            return False
        self._seen.add(number)
        if len(self._seen) > 4 * PLAN_EVENTS_KEPT:
            oldest = sorted(self._seen)[: 2 * PLAN_EVENTS_KEPT]
            self._seen.difference_update(oldest)
        self.events.append(event)
        kind, subject = event.kind, event.subject
        if kind in _PLAN_KINDS:
            self.plan_events.append(event)
        if kind == "FAULT" and subject in self.robot.components:
            self.repairing.add(subject)
        elif kind == "COMPONENT_RESET":
            self.repairing.discard(subject)
        return True

    def set_lifecycle(self, state: ComponentState) -> None:
        self.lifecycles[state.component] = state
        if state.state is Lifecycle.READY:
            self.repairing.discard(state.component)

    def set_diagnosis(self, diagnosis: DiagnosisInfo | None) -> None:
        self.diagnosis = diagnosis

    def add_observation(self, payload: Mapping[str, Any], now: float | None = None) -> Track:
        resource = payload.get("resource") or []
        if isinstance(resource, str):
            resource = [resource]
        key = "|".join(
            [str(payload.get("observer", payload.get("type", ""))), ",".join(map(str, resource)),
             ",".join(map(str, payload.get("callerids") or []))]
        )  # fmt: skip
        track = self.tracks.get(key)
        if track is None:
            track = self.tracks[key] = Track(key, dict(payload))
        track.latest = dict(payload)
        stamp = payload.get("stamp")
        at = float(stamp) if isinstance(stamp, int | float) else time.time()
        track.history.append((at, _numbers(payload.get("values"))))
        horizon = (now if now is not None else at) - OBSERVATION_HISTORY
        while track.history and track.history[0][0] < horizon:
            track.history.popleft()
        return track

    # --- views --------------------------------------------------------------------------

    @property
    def diagnosed(self) -> frozenset[str]:
        if self.diagnosis is None or self.diagnosis.status == "OK":
            return frozenset()
        return self.diagnosis.possibly_faulty

    def active_tasks(self) -> list[ExecutorTask]:
        return [t for t in self.tasks if t.state in ("starting", "running", "paused")]

    def graph_state(self) -> graph.GraphState:
        diagnosed = self.diagnosed
        states = {}
        faults = {}
        for name, spec in self.robot.components.items():
            record = self.faults.get(name)
            permanent = (record is not None and record.permanent_fault) or name in self.unusable
            states[name] = component_state(
                self.lifecycles.get(name),
                permanent=permanent,
                faulty=name in diagnosed or name in self.repairing,
            )
            limit = spec.max_faults if isinstance(spec, FunctionalitySpec) else 0
            if record is not None and record.fault_count:
                faults[name] = (record.fault_count, limit)
        serves: dict[str, list[str]] = {}
        used: set[tuple[str, str]] = set()
        for task in self.active_tasks():
            label = f"task {task.id} {task.name}"
            used.update(task.providers.items())
            for name in [*task.functionalities, task.behavior]:
                if name:
                    serves.setdefault(name, []).append(label)
        topics = set(self.robot.topics)
        failed = {
            str(r)
            for observer in (self.diagnosis.failed if self.diagnosis and diagnosed else ())
            for r in observer.get("resource", []) if str(r) in topics
        }  # fmt: skip
        return graph.GraphState(
            states=states,
            diagnosed=diagnosed,
            faults=faults,
            failed_topics=frozenset(failed),
            tasks={k: tuple(v) for k, v in serves.items()},
            used=frozenset(used),
        )

    def view(self, name: str, now: float | None = None) -> dict[str, Any]:
        """One of :data:`VIEWS` as a JSON object."""
        now = time.time() if now is None else now
        if name == "status":
            return {
                "robot": self.robot.name,
                "alive": self.alive,
                "problem": self.problem,
                "fleet": self.fleet,
            }
        if name == "goals":
            return {"goals": plain(self.goals)}
        if name == "plan":
            return self.plan_view(now)
        if name == "components":
            return self.components_view()
        if name == "observations":
            return {"observations": [t.view() for t in self.tracks.values()], "now": now}
        if name == "events":
            return {"events": [event_item(e) for e in self.events]}
        raise KeyError(name)

    def plan_view(self, now: float) -> dict[str, Any]:
        if self.plan is None:
            return {"plan": None, "title": "no plan yet", "svg": "", "steps": []}
        chart = gantt.live_gantt(
            self.plan, self.execution, self.plan_events, self.tasks, now, robots=self.robots
        )
        return {
            "plan": self.plan.id,
            "state": self.plan.state.value,
            "title": chart.title,
            "svg": svg.inline(gantt.render(chart, titled=False)),  # the page shows the title
            "steps": [
                {"index": s.index, "label": s.label, "state": s.state, "details": s.details}
                for s in chart.steps
            ],
        }

    def components_view(self) -> dict[str, Any]:
        state = self.graph_state()
        components = []
        for name, spec in self.robot.components.items():
            lifecycle = self.lifecycles.get(name)
            record = self.faults.get(name)
            components.append(
                {
                    "name": name,
                    "kind": spec.kind.value,
                    "state": state.states.get(name, "stopped"),
                    "lifecycle": lifecycle.state.value if lifecycle else "stopped",
                    "pid": lifecycle.pid if lifecycle else None,
                    "reason": (lifecycle.reason if lifecycle else "")
                    or (record.reason if record else ""),
                    # what its process wrote last when it failed: its exception
                    "output": list(lifecycle.output) if lifecycle else [],
                    "faults": record.fault_count if record else 0,
                    "max_faults": spec.max_faults if isinstance(spec, FunctionalitySpec) else None,
                    "permanent": state.states.get(name) == "permanently faulty",
                    "diagnosed": name in state.diagnosed,
                    "tasks": list(state.tasks.get(name, ())),
                }
            )
        configurations = [
            {"id": t.id, "name": t.name, "behavior": t.behavior, "state": t.state,
             "providers": dict(t.providers)}
            for t in self.active_tasks()
        ]  # fmt: skip
        return {
            "svg": svg.inline(graph.render(self.layout, state)),
            "components": components,
            "configurations": configurations,
            "diagnosis": plain(self.diagnosis) if self.diagnosis is not None else {},
        }
