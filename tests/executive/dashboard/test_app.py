"""The dashboard's web application over HTTP, against a scripted executive: the verbs
answered by a test on a real bus, so every answer is known in advance."""

from __future__ import annotations

import dataclasses
import json
import threading
import urllib.error
import urllib.request
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from typing import Any

import pytest

from executive.bus.api import components, monitoring, planning, tasks
from executive.bus.keys import EVENTS
from executive.bus.payloads import DiagnosisInfo
from executive.bus.reports import ExecutionStatus, StepStatus
from executive.bus.schema import read
from executive.bus.session import Bus
from executive.dashboard.server import Dashboard, DashboardError
from knowledge.errors import DomainError
from knowledge.records import ComponentRecord, Goal, GoalState, Plan
from knowledge.robot import load_robot
from tests.conftest import USECASE, free_endpoint

PLAN: Plan = read(Plan, {
    "id": 1, "state": "executing", "engine": "kairos", "goal_ids": [1], "reason": "",
    "created": 100.0, "updated": 100.0,
    "steps": [
        {"index": 0, "action": "move_to", "args": ["dock", "lab"], "start": 0.0, "duration": 5.0},
        {"index": 1, "action": "take_picture", "args": ["lab"], "start": 5.0, "duration": 2.0},
    ],
}, "plan")  # fmt: skip
EXECUTION = ExecutionStatus(
    plan=1,
    steps=(
        StepStatus(0, "move_to(dock, lab)", "running"),
        StepStatus(1, "take_picture(lab)", "pending"),
    ),
)


def goal(number: int, expression: str, state: str = "pending") -> Goal:
    return Goal(number, expression, GoalState(state), created=1.0, updated=1.0)


@dataclass
class ScriptedExecutive:
    """The executive's verbs, answered from these fields; what it was asked is kept."""

    bus: Bus
    goals: list[Goal] = field(default_factory=list)
    added: list[planning.GoalAdd] = field(default_factory=list)
    cancelled: list[int] = field(default_factory=list)

    def serve(self) -> None:
        bus = self.bus
        planning.GOAL_LIST.serve(bus, lambda _: planning.GoalsReply(self.goals))
        planning.GOAL_ADD.serve(bus, self.add)
        planning.GOAL_CANCEL.serve(bus, self.cancel)
        planning.PLAN_SHOW.serve(bus, lambda _: planning.PlanReply(PLAN, EXECUTION))
        planning.EVENTS.serve(bus, lambda _: planning.EventsReply([]))
        planning.STATUS.serve(
            bus,
            lambda _: planning.StatusReply(
                "usecase", self.goals, PLAN, EXECUTION, DiagnosisInfo("OK"),
                [ComponentRecord("lidar", 10.0, fault_count=1, reason="x", updated=1.0)],
            ),
        )  # fmt: skip
        tasks.TASK_LIST.serve(bus, lambda _: tasks.TasksReply([]))
        tasks.SCHEDULE_SHOW.serve(bus, lambda _: tasks.ScheduleReply([], [], []))
        components.COMPONENT_LIST.serve(bus, lambda _: components.ComponentsReply([]))
        monitoring.OBSERVER_LATEST.serve(bus, lambda _: monitoring.LatestReply([]))

    def add(self, request: planning.GoalAdd) -> planning.GoalReply:
        if "lob" in request.expression:
            raise DomainError(f"goal '{request.expression}': unknown object 'lob'")
        self.added.append(request)
        self.goals.append(goal(len(self.goals) + 1, request.expression))
        return planning.GoalReply(self.goals[-1])

    def cancel(self, request: planning.GoalId) -> planning.GoalReply:
        self.cancelled.append(request.id)
        cancelled = dataclasses.replace(self.goals[request.id - 1], state=GoalState.CANCELLED)
        return planning.GoalReply(cancelled)


@pytest.fixture(scope="module")
def served() -> Iterator[tuple[ScriptedExecutive, Dashboard]]:
    endpoint = free_endpoint()
    with Bus("usecase", name="executive", endpoint=endpoint, listen=True) as bus:
        executive = ScriptedExecutive(bus, [goal(1, "(picture_taken lab)", "executing")])
        executive.serve()
        with Dashboard.connect(load_robot(USECASE), endpoint, port=0, folders=[]) as dashboard:
            yield executive, dashboard


def request(
    dashboard: Dashboard, path: str, body: Any = None, headers: dict[str, str] | None = None
) -> tuple[int, Any]:
    data = None if body is None else json.dumps(body).encode()
    sent = {"content-type": "application/json", **(headers or {})}
    url = f"http://127.0.0.1:{dashboard.port}{path}"
    try:
        with urllib.request.urlopen(urllib.request.Request(url, data, sent), timeout=10) as r:
            raw = r.read()
            kind = r.headers.get("content-type", "")
            return r.status, json.loads(raw) if "json" in kind else raw.decode()
    except urllib.error.HTTPError as e:
        raw = e.read()
        try:
            return e.code, json.loads(raw)
        except ValueError:
            return e.code, raw.decode()


def stream(
    dashboard: Dashboard,
    until: str,
    where: Callable[[dict[str, Any]], bool] = lambda _: True,
    timeout: float = 10.0,
) -> dict[str, Any]:
    """The first server-sent event called ``until`` whose data fits ``where`` (the
    dashboard may still be asking the executive when a page connects)."""
    url = f"http://127.0.0.1:{dashboard.port}/api/stream"
    with urllib.request.urlopen(url, timeout=timeout) as response:
        name = ""
        for raw in response:
            line = raw.decode().rstrip("\n")
            if line.startswith("event: "):
                name = line[7:]
            elif line.startswith("data: ") and name == until:
                data: dict[str, Any] = json.loads(line[6:])
                if where(data):
                    return data
    raise AssertionError(f"the stream ended before a '{until}' event")


def test_the_page_and_its_assets_are_served_from_the_dashboard_itself(served: Any) -> None:
    _, dashboard = served
    status, page = request(dashboard, "/")
    assert status == 200 and "/static/dashboard.js" in page
    assert "http://" not in page and "https://" not in page  # no CDN: a robot has no internet
    for asset in ("/static/dashboard.js", "/static/dashboard.css"):
        assert request(dashboard, asset)[0] == 200


def test_the_stream_starts_with_every_view_of_the_robot(served: Any) -> None:
    _, dashboard = served
    status = stream(dashboard, "status")
    assert status["robot"] == "usecase"
    goals = stream(dashboard, "goals", lambda view: bool(view["goals"]))
    assert [g["expression"] for g in goals["goals"]][:1] == ["(picture_taken lab)"]
    plan = stream(dashboard, "plan", lambda view: view["plan"] is not None)
    assert plan["plan"] == 1 and [s["label"] for s in plan["steps"]] == [
        "move_to(dock, lab)",
        "take_picture(lab)",
    ]
    assert plan["svg"].startswith("<svg") and "move_to(dock, lab)" in plan["svg"]
    components_view = stream(
        dashboard, "components", lambda view: any(c["faults"] for c in view["components"])
    )
    lidar = next(c for c in components_view["components"] if c["name"] == "lidar")
    assert lidar["faults"] == 1 and 'data-node="lidar"' in components_view["svg"]


def test_a_goal_added_on_the_page_goes_through_the_goal_add_verb(served: Any) -> None:
    executive, dashboard = served
    status, answer = request(dashboard, "/api/goals", {"expression": "(robot_at lab)",
                                                       "priority": 3, "deadline": 60})  # fmt: skip
    assert status == 200 and answer["goal"]["expression"] == "(robot_at lab)"
    sent = executive.added[-1]
    assert (sent.expression, sent.priority, sent.deadline, sent.source) == (
        "(robot_at lab)", 3, 60.0, "user"
    )  # fmt: skip


def test_a_refused_goal_answers_with_the_executives_reason(served: Any) -> None:
    _, dashboard = served
    status, answer = request(dashboard, "/api/goals", {"expression": "(picture_taken lob)"})
    assert status == 400 and "unknown object 'lob'" in answer["error"]
    status, answer = request(dashboard, "/api/goals", {"expression": "(robot_at lab)",
                                                       "priority": "high"})  # fmt: skip
    assert status == 400 and "'priority' must be an integer" in answer["error"]


def test_a_goal_cannot_pretend_to_come_from_a_rule(served: Any) -> None:
    executive, dashboard = served
    request(dashboard, "/api/goals", {"expression": "(robot_at dock)", "source": "rule"})
    assert executive.added[-1].source == "user"


def test_a_goal_is_cancelled_through_the_goal_cancel_verb(served: Any) -> None:
    executive, dashboard = served
    status, answer = request(dashboard, "/api/goals/1/cancel", {})
    assert status == 200 and answer["goal"]["state"] == "cancelled"
    assert executive.cancelled[-1] == 1
    assert request(dashboard, "/api/goals/x/cancel", {})[0] == 400


def test_changes_come_only_as_json_from_the_dashboards_own_page(served: Any) -> None:
    _, dashboard = served
    form = {"content-type": "application/x-www-form-urlencoded"}
    assert request(dashboard, "/api/goals", {"expression": "(robot_at lab)"}, form)[0] == 415
    foreign = {"origin": "http://evil.example"}
    status, text = request(dashboard, "/api/goals", {"expression": "(robot_at lab)"}, foreign)
    assert status == 403 and "own page" in text


def test_a_loopback_dashboard_answers_only_to_loopback_names(served: Any) -> None:
    _, dashboard = served
    status, _ = request(dashboard, "/", headers={"host": f"evil.example:{dashboard.port}"})
    assert status == 421
    assert request(dashboard, "/", headers={"host": f"localhost:{dashboard.port}"})[0] == 200


def test_an_event_published_on_the_bus_reaches_the_page_live(served: Any) -> None:
    executive, dashboard = served
    found: dict[str, Any] = {}

    def read() -> None:
        found.update(stream(dashboard, "event"))

    reader = threading.Thread(target=read)
    reader.start()
    for number in range(1000, 1050):  # until the reader's stream is open
        executive.bus.publish(
            EVENTS, {"id": number, "stamp": 1.0, "kind": "FAULT", "subject": "lidar", "data": {}}
        )
        reader.join(0.1)
        if not reader.is_alive():
            break
    reader.join(10)
    assert found["events"][0]["kind"] == "FAULT" and found["events"][0]["subject"] == "lidar"


def test_a_dashboard_beyond_loopback_needs_the_robots_credentials(served: Any) -> None:
    executive, _ = served
    anywhere = "0.0.0.0"  # noqa: S104 - asked for, and refused
    with pytest.raises(DashboardError, match=r"\(beyond loopback\) only with the robot's bus"):
        Dashboard(load_robot(USECASE), executive.bus, host=anywhere, port=0)


def test_the_pictures_are_served_as_svg_files(served: Any) -> None:
    _, dashboard = served
    stream(dashboard, "plan", lambda view: view["plan"] is not None)
    status, picture = request(dashboard, "/api/graph.svg")
    assert status == 200 and picture.startswith("<?xml") and "cam_to_lidar" in picture
    status, picture = request(dashboard, "/api/plan.svg")
    assert status == 200 and "take_picture(lab)" in picture
