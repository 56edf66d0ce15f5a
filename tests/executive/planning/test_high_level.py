"""The high level as a service: goals, plans, state and events over the bus and the CLI.

A real bus, knowledge base and Kairos worker; the scripted runner stands in for the
task executor (tested on its own), so these tests are about the goal interface.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path

import pytest

from executive.bus.api import components, monitoring, tasks
from executive.bus.api.planning import EVENTS as EVENTS_API
from executive.bus.api.planning import (
    GOAL_LIST,
    GOAL_SHOW,
    RECENT_GOALS,
    STATUS,
    GoalId,
    GoalQuery,
    newest_goals,
)
from executive.bus.event_relay import EventRelay
from executive.bus.keys import EVENTS
from executive.bus.lifecycle_manager import LifecycleManager
from executive.bus.reports import RoundPhase
from executive.bus.service import Context, ServiceState
from executive.bus.session import Bus
from executive.dashboard.feed import RECENT_GOALS as RECENT_SHOWN
from executive.dashboard.server import Dashboard
from executive.planning.goals import submit
from executive.planning.high_level import HighLevel
from executive.testing.client import RobotClient
from executive.testing.harness import robot_variant
from knowledge.errors import DuraError
from knowledge.knowledge_base import KnowledgeBase
from knowledge.records import Fact, GoalState, PlanState
from knowledge.robot import load_robot
from tests.conftest import ROOT, USECASE, run_dura, wait_for
from tests.executive.dashboard.test_app import stream
from tests.executive.planning import slow_engine
from tests.executive.planning.scripted_runner import ScriptedRunner

Run = Callable[..., subprocess.CompletedProcess[str]]


@dataclass
class Robot:
    kb: KnowledgeBase
    bus: Bus
    runner: ScriptedRunner
    high: HighLevel
    dura: Run


@pytest.fixture
def robot(tmp_path: Path, endpoint: str) -> Iterator[Robot]:
    description = load_robot(USECASE)
    runner = ScriptedRunner(delay=0.05)
    with (
        Bus(description.name, name="executive", endpoint=endpoint, listen=True) as bus,
        KnowledgeBase(tmp_path / "kb.db") as kb,
    ):
        context = Context(description, bus, kb)
        relay = EventRelay(context)
        high = HighLevel(context, lambda: runner, events=relay)
        with LifecycleManager([relay, high]):
            assert high.wait_for(ServiceState.ACTIVE, 60)

            def dura(*args: str) -> subprocess.CompletedProcess[str]:
                return run_dura(*args, "--robot", str(USECASE), "--endpoint", endpoint)

            yield Robot(kb, bus, runner, high, dura)


def state_of(robot: Robot, goal_id: int) -> GoalState:
    return robot.kb.goal(goal_id).state


def test_goals_submitted_through_the_cli_are_planned_executed_and_achieved(
    robot: Robot,
) -> None:
    heard: list[dict[str, object]] = []
    robot.bus.subscribe(EVENTS, lambda m: heard.append(m.payload))
    done = robot.dura("goal", "add", "(picture_taken lab)", "--priority", "2", "--json")
    assert done.returncode == 0, done.stderr
    goal = json.loads(done.stdout)
    assert (goal["expression"], goal["priority"], goal["source"]) == (
        "(picture_taken lab)",
        2,
        "user",
    )
    assert wait_for(lambda: state_of(robot, goal["id"]) is GoalState.ACHIEVED, 60)
    assert robot.runner.labels() == ["move_to(dock, lab)", "take_picture(lab)"]
    listed = json.loads(robot.dura("goal", "list", "--json").stdout)["goals"]
    assert [(g["id"], g["state"]) for g in listed] == [(goal["id"], "achieved")]
    shown = robot.dura("goal", "show", str(goal["id"]))
    assert "state achieved" in shown.stdout and "GOAL_ACHIEVED" in shown.stdout
    kinds = [e["kind"] for e in heard]
    for kind in ("GOAL_ADDED", "PLAN_START", "DISPATCH", "START", "END", "GOAL_ACHIEVED"):
        assert kind in kinds
    trace = robot.dura("events", "-n", "100")
    assert "DISPATCH" in trace.stdout and "take_picture(lab)" in trace.stdout


def test_a_goal_naming_an_unknown_object_is_refused_in_one_line_and_not_stored(
    robot: Robot,
) -> None:
    done = robot.dura("goal", "add", "(picture_taken lob)")
    assert done.returncode == 1
    assert done.stderr.startswith("dura: goal '(picture_taken lob)': unknown object 'lob'")
    assert len(done.stderr.splitlines()) == 1
    assert robot.kb.goals() == []


def test_the_plan_is_shown_as_a_timeline_with_the_state_of_each_step(robot: Robot) -> None:
    robot.runner.held.add("take_picture")
    goal = json.loads(robot.dura("goal", "add", "(picture_taken office)", "--json").stdout)
    robot.runner.wait_for("take_picture(office)")
    shown = robot.dura("plan", "show")
    assert shown.returncode == 0, shown.stderr
    lines = shown.stdout.splitlines()
    assert lines[0].startswith("plan 1: executing, by kairos, for goal 1")
    assert lines[1].split()[:6] == ["#", "START", "DURATION", "STEP", "STATE", "TIMELINE"]
    assert "take_picture(office)" in shown.stdout and "running" in shown.stdout
    status = json.loads(robot.dura("status", "--json").stdout)
    assert [g["id"] for g in status["goals"]] == [goal["id"]]
    assert status["plan"]["id"] == 1
    robot.dura("goal", "cancel", str(goal["id"]))
    assert state_of(robot, goal["id"]) is GoalState.CANCELLED


def test_cancelling_the_only_goal_of_a_plan_ends_the_plan_and_its_steps_show_it(
    robot: Robot,
) -> None:
    robot.runner.held.add("move_to")
    goal = json.loads(robot.dura("goal", "add", "(picture_taken lab)", "--json").stdout)
    move = robot.runner.wait_for("move_to(dock, lab)")
    assert wait_for(lambda: robot.kb.plan(1).steps[0].state == "running", 10)

    assert robot.dura("goal", "cancel", str(goal["id"])).returncode == 0

    plan = robot.kb.plan(1)  # ended before the cancel was answered
    assert (plan.state, plan.reason) == (
        PlanState.CANCELLED,
        "goal 1 cancelled: no goal of the plan is open",
    )
    assert [s.state for s in plan.steps] == ["cancelled", "pending"]
    assert move.calls[-1] == "cancel"
    assert robot.kb.facts("robot_at") == [Fact("robot_at", ("dock",))]  # taken back
    shown = robot.dura("plan", "show").stdout.splitlines()
    assert shown[0].startswith("plan 1: cancelled")
    assert "cancelled" in next(line for line in shown if "move_to(dock, lab)" in line)
    assert "pending" in next(line for line in shown if "take_picture(lab)" in line)
    status = json.loads(robot.dura("status", "--json").stdout)
    assert status["plan"]["state"] == "cancelled"
    assert [s["state"] for s in status["plan"]["steps"]] == ["cancelled", "pending"]
    text = robot.dura("status").stdout.splitlines()
    assert "cancelled" in next(line for line in text if "move_to(dock, lab)" in line)
    kb = run_dura("kb", "show", "--db", str(robot.kb.path)).stdout
    plans = kb.split("plans")[1].split("tasks")[0]
    assert "cancelled" in plans and "2: 1 cancelled, 1 pending" in plans


def test_facts_and_objects_are_read_and_changed_through_the_cli(robot: Robot) -> None:
    shown = robot.dura("state", "get", "(robot_at *)")
    assert shown.stdout.splitlines()[1].split() == ["(robot_at", "dock)", "true"]
    assert robot.dura("object", "add", "hall", "place").returncode == 0
    assert robot.kb.objects()["hall"] == "place"
    assert robot.dura("state", "set", "(photographable hall)").returncode == 0
    assert robot.dura("state", "set", "(= (travel_time dock hall) 2)").returncode == 0
    values = json.loads(robot.dura("state", "get", "travel_time", "--json").stdout)["facts"]
    assert {"name": "travel_time", "args": ["dock", "hall"], "value": 2.0} in [
        {k: f[k] for k in ("name", "args", "value")} for f in values
    ]
    assert robot.dura("state", "unset", "(photographable hall)").returncode == 0
    assert all(f.name != "photographable" or f.args != ("hall",) for f in robot.kb.facts())
    wrong = robot.dura("state", "set", "(robot_at nowhere)")
    assert wrong.returncode == 1 and "unknown object 'nowhere'" in wrong.stderr
    wrong = robot.dura("object", "add", "shelf", "furniture")
    assert wrong.returncode == 1 and "unknown type 'furniture'" in wrong.stderr
    assert "shelf" not in robot.kb.objects()


def test_a_fact_pattern_with_a_misspelt_name_is_refused_with_a_suggestion(robot: Robot) -> None:
    wrong = robot.dura("state", "get", "(robot_a *)")
    assert wrong.returncode == 1
    assert wrong.stderr.strip() == (
        "dura: fact pattern '(robot_a *)': unknown predicate or function 'robot_a' "
        "(did you mean 'robot_at'?)"
    )
    assert robot.dura("state", "get", "(robot_at lab)").stdout.splitlines()[1:] == []


def test_a_failed_task_is_replanned_and_the_goal_still_achieved(robot: Robot) -> None:
    robot.runner.fail_once["move_to(dock, lab)"] = "the base stalled"
    goal = json.loads(robot.dura("goal", "add", "(robot_at lab)", "--json").stdout)
    assert wait_for(lambda: state_of(robot, goal["id"]) is GoalState.ACHIEVED, 60)
    kinds = [e.kind for e in robot.kb.events()]
    assert "FAIL" in kinds and "REPLAN" in kinds


def test_an_integrity_goal_is_posted_when_lidar_becomes_permanently_faulty(
    robot: Robot,
) -> None:
    robot.kb.update_facts(add=[Fact("robot_at", ("lab",))], remove=[Fact("robot_at", ("dock",))])
    robot.kb.register_component("lidar", 1.0)
    robot.kb.mark_permanent_fault("lidar", "three faults")
    assert wait_for(lambda: any(g.source == "integrity" for g in robot.kb.goals()), 30)
    goal = next(g for g in robot.kb.goals() if g.source == "integrity")
    assert (goal.expression, goal.priority) == ("(robot_at dock)", 10)
    assert wait_for(lambda: state_of(robot, goal.id) is GoalState.ACHIEVED, 60)


def test_events_follow_prints_new_events_as_they_happen(robot: Robot, endpoint: str) -> None:
    follower = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "executive.cli",
            "events",
            "--follow",
            "-n",
            "1",
            "--robot",
            str(USECASE),
            "--endpoint",
            endpoint,
        ],
        stdout=subprocess.PIPE,
        text=True,
    )
    try:
        assert follower.stdout is not None
        assert follower.stdout.readline()  # the newest event: it follows from there
        robot.dura("goal", "add", "(picture_taken lab)")
        line = follower.stdout.readline()
        assert "GOAL_ADDED" in line and "goal 1" in line
    finally:
        follower.terminate()
        follower.wait(10)


def test_a_high_level_with_nothing_to_run_its_steps_fails_with_the_reason(
    tmp_path: Path, endpoint: str
) -> None:
    def no_runner() -> ScriptedRunner:
        raise DuraError("the task executor has not started")

    description = load_robot(USECASE)
    with (
        Bus(description.name, name="executive", endpoint=endpoint, listen=True) as bus,
        KnowledgeBase(tmp_path / "kb.db") as kb,
    ):
        context = Context(description, bus, kb)
        relay = EventRelay(context)
        high = HighLevel(context, no_runner, events=relay)
        failures: list[str] = []
        with LifecycleManager([relay, high], on_failure=failures.append):
            assert not high.wait_for(ServiceState.ACTIVE, 60)  # it ends in error instead
            assert high.state is ServiceState.ERROR
            assert failures == ["the task executor has not started"]
            with pytest.raises(DuraError, match="cannot plan: the task executor has not"):
                high.deliberation  # noqa: B018 (the property raises)


def test_without_an_executive_goal_commands_say_so(endpoint: str) -> None:
    done = run_dura("goal", "list", "--robot", str(USECASE), "--endpoint", endpoint)
    assert done.returncode == 1
    assert done.stderr.startswith(f"dura: no executive for robot 'usecase' at {endpoint}")


CLI_THINK = 4.0  # seconds a plan takes when the cancel comes from ``dura``: a fresh
# interpreter needs up to 2 s to start on a busy machine


@pytest.fixture
def slow_robot(tmp_path: Path, endpoint: str, monkeypatch: pytest.MonkeyPatch) -> Iterator[Robot]:
    """The use-case robot planning with a Kairos that takes CLI_THINK s for every plan."""
    plugins = slow_engine.register(tmp_path / "plugins")
    monkeypatch.syspath_prepend(str(plugins))
    monkeypatch.setenv("PYTHONPATH", os.pathsep.join((str(plugins), str(ROOT))))
    monkeypatch.setenv(slow_engine.THINK_VARIABLE, str(CLI_THINK))
    variant = robot_variant(USECASE, tmp_path / "robot", {"planner": {"engine": slow_engine.NAME}})
    description = load_robot(variant)
    runner = ScriptedRunner(delay=0.05)
    with (
        Bus(description.name, name="executive", endpoint=endpoint, listen=True) as bus,
        KnowledgeBase(tmp_path / "kb.db") as kb,
    ):
        context = Context(description, bus, kb)
        relay = EventRelay(context)
        high = HighLevel(context, lambda: runner, events=relay)
        with LifecycleManager([relay, high]):
            assert high.wait_for(ServiceState.ACTIVE, 60)

            def dura(*args: str) -> subprocess.CompletedProcess[str]:
                return run_dura(*args, "--robot", str(USECASE), "--endpoint", endpoint)

            yield Robot(kb, bus, runner, high, dura)


def test_a_goal_cancelled_while_its_plan_is_computed_is_never_planned_or_executed(
    slow_robot: Robot,
) -> None:
    robot = slow_robot
    domain = robot.high.deliberation.domain
    with robot.kb.transaction():  # both goals in the same round
        office = submit(robot.kb, domain, "(picture_taken office)", priority=5)
        lab = submit(robot.kb, domain, "(robot_at lab)")
    robot.high.deliberation.goals.wake("two goals added")
    assert wait_for(
        lambda: robot.high.deliberation.goals.status().phase is RoundPhase.SEARCHING, 30
    )
    assert robot.kb.events(kind="PLANNING")[0].data["goals"] == [office.id, lab.id]

    cancel = robot.dura("goal", "cancel", str(office.id))  # while kairos-slow plans

    assert cancel.returncode == 0, cancel.stderr
    assert cancel.stdout.strip() == f"goal {office.id}: cancelled"
    assert wait_for(lambda: state_of(robot, lab.id) is GoalState.ACHIEVED, 60)
    first, again = robot.kb.events(kind="PLANNING")
    (cancelled,) = robot.kb.events(kind="GOAL_CANCELLED")
    assert first.stamp < cancelled.stamp < again.stamp  # the cancel came during the search
    assert again.data["reason"] == f"goals {office.id} cancelled while planning"
    assert again.data["goals"] == [lab.id]
    assert again.stamp - first.stamp >= CLI_THINK
    # the cancelled goal was never planned or executed: one plan, for the other goal
    assert state_of(robot, office.id) is GoalState.CANCELLED
    history = [e.kind for e in robot.kb.events() if e.subject == f"goal {office.id}"]
    assert history == ["GOAL_ADDED", "GOAL_CANCELLED"]
    assert [p.goal_ids for p in robot.kb.plans()] == [(lab.id,)]
    assert robot.runner.labels() == ["move_to(dock, lab)"]
    assert [e.data["goals"] for e in robot.kb.events(kind="PLAN_START")] == [[lab.id]]
    status = json.loads(robot.dura("status", "--json").stdout)
    assert status["planning"]["planning"] is False
    print(
        f"search {again.stamp - first.stamp:.2f} s, cancel after {cancelled.stamp - first.stamp:.2f} s"
    )


def test_cancelling_a_goal_that_ended_says_so_and_changes_nothing(robot: Robot) -> None:
    goal = json.loads(robot.dura("goal", "add", "(robot_at lab)", "--json").stdout)
    assert wait_for(lambda: state_of(robot, goal["id"]) is GoalState.ACHIEVED, 60)
    done = robot.dura("goal", "cancel", str(goal["id"]))
    assert done.returncode == 1
    assert done.stderr.strip() == f"dura: goal {goal['id']} is achieved already"
    missing = robot.dura("goal", "cancel", "99")
    assert (missing.returncode, missing.stderr.strip()) == (1, "dura: no goal 99")
    assert state_of(robot, goal["id"]) is GoalState.ACHIEVED


def test_a_malformed_request_is_refused_by_its_declared_type(robot: Robot) -> None:
    with pytest.raises(DuraError, match=r"goal/show: 'id' must be an integer, not \"one\""):
        robot.bus.request(GOAL_SHOW.key, {"id": "one"})
    with pytest.raises(DuraError, match=r"events: 'limit' must be from 0 to"):
        robot.bus.request(EVENTS_API.key, {"limit": -1})
    listed = GOAL_LIST.call(robot.bus, GoalQuery([GoalState.PENDING]))
    assert listed.goals == []


def test_a_goal_s_history_is_read_page_by_page_from_its_first_event(robot: Robot) -> None:
    """A robot's log is long: a goal's history is read from the goal's first event on, a
    page at a time (not the whole log at once), and no event of it is missed."""
    robot.kb.log_event("NOTE", "before", {"goals": [1]})  # before goal 1 was added
    goal = robot.kb.add_goal("(picture_taken lab)")
    with robot.kb.transaction():
        for n in range(2_500):  # more than two pages of other events
            robot.kb.log_event("NOTE", f"goal {goal.id + 1 + n}", {"goals": [goal.id + 1]})
    robot.kb.log_event("NOTE", "late", {"goals": [goal.id]})
    history = GOAL_SHOW.call(robot.bus, GoalId(goal.id))
    mine = [e for e in history.events if e.kind == "NOTE"]
    assert [e.subject for e in mine] == ["late"]
    assert history.events[0].kind == "GOAL_ADDED"


def test_a_goal_unreachable_until_dura_state_set_is_then_achieved(robot: Robot) -> None:
    goal = json.loads(robot.dura("goal", "add", "(picture_taken dock)", "--json").stdout)
    assert wait_for(lambda: state_of(robot, goal["id"]) is GoalState.UNREACHABLE, 60)
    assert "needs (photographable dock)" in robot.kb.goal(goal["id"]).reason
    assert robot.dura("state", "set", "(photographable dock)").returncode == 0
    assert wait_for(lambda: state_of(robot, goal["id"]) is GoalState.ACHIEVED, 60)
    pending = [e for e in robot.kb.events(kind="GOAL_PENDING") if e.subject == f"goal {goal['id']}"]
    assert [e.data["reason"] for e in pending] == [
        "reachable again after STATE_SET (photographable dock)"
    ]


def test_a_maintenance_goal_is_reposted_when_the_plan_takes_it_away(robot: Robot) -> None:
    home = json.loads(robot.dura("goal", "add", "(robot_at dock)", "--keep", "--json").stdout)
    assert home["keep"] is True
    assert wait_for(lambda: state_of(robot, home["id"]) is GoalState.ACHIEVED, 30)
    listed = robot.dura("goal", "list").stdout.splitlines()
    assert listed[1].split()[:3] == [str(home["id"]), "achieved,", "watched"], listed
    picture = json.loads(robot.dura("goal", "add", "(picture_taken lab)", "--json").stdout)
    assert wait_for(lambda: state_of(robot, picture["id"]) is GoalState.ACHIEVED, 60)
    assert wait_for(
        lambda: any(
            e.subject == f"goal {home['id']}" for e in robot.kb.events(kind="GOAL_PENDING")
        ),
        30,
    )
    assert wait_for(lambda: state_of(robot, home["id"]) is GoalState.ACHIEVED, 60)
    assert wait_for(lambda: Fact("robot_at", ("dock",)) in robot.kb.facts(), 30)


def test_a_dry_run_plans_on_the_live_state_and_changes_nothing(robot: Robot) -> None:
    robot.runner.held.add("take_picture")
    goal = json.loads(robot.dura("goal", "add", "(picture_taken office)", "--json").stdout)
    robot.runner.wait_for("take_picture(office)")  # the robot is at the office, taking it
    started = [("START", "take_picture(office)")]  # logged once the runner's report is in
    assert wait_for(lambda: [(e.kind, e.subject) for e in robot.kb.events()[-1:]] == started, 10)
    plans, events = len(robot.kb.plans()), len(robot.kb.events())
    dry = robot.dura("plan", "--dry-run", "--json")
    assert dry.returncode == 0, dry.stderr
    reply = json.loads(dry.stdout)
    assert (reply["status"], reply["planned"], reply["goals"]) == (
        "solved",
        [goal["id"]],
        [goal["id"]],
    )
    assert [(s["action"], s["args"]) for s in reply["steps"]] == [("take_picture", ["office"])]
    assert (len(robot.kb.plans()), len(robot.kb.events())) == (plans, events)
    shown = robot.dura("plan", "--dry-run")
    assert f"for goal {goal['id']} (nothing executed)" in shown.stdout
    assert "dry run: 1 step, makespan" in shown.stdout
    robot.runner.wait_for("take_picture(office)").end(None)
    assert wait_for(lambda: state_of(robot, goal["id"]) is GoalState.ACHIEVED, 30)
    assert "dry run: nothing to plan (no open goals)" in robot.dura("plan", "--dry-run").stdout


def test_a_dry_run_plans_for_a_goal_asked_about_without_adding_it(robot: Robot) -> None:
    stored = (robot.kb.goals(), len(robot.kb.plans()), len(robot.kb.events()))
    asked = ["(picture_taken office)", "(robot_at  dock)"]
    dry = robot.dura("plan", "--dry-run", "--goal", asked[0], "--goal", asked[1])
    assert dry.returncode == 0, dry.stderr
    lines = dry.stdout.splitlines()
    assert lines[0] == "(robot_at dock): holds already", lines
    assert lines[1].startswith("dry run: 2 steps, makespan 7 s, by kairos in "), lines
    assert lines[1].endswith(" for (picture_taken office) (nothing executed)"), lines
    assert [line.split()[3] for line in lines[3:]] == ["move_to(dock,", "take_picture(office)"]
    reply = json.loads(robot.dura("plan", "--dry-run", "--goal", asked[0], "--json").stdout)
    assert (reply["asked"], reply["goals"], reply["planned"]) == ([asked[0]], [-1], [-1])
    wrong = robot.dura("plan", "--dry-run", "--goal", "(picture_taken lob)")
    assert wrong.returncode == 1
    assert wrong.stderr.strip().splitlines() == [
        "dura: goal '(picture_taken lob)': unknown object 'lob' (did you mean 'lab'?)"
    ]
    assert (robot.kb.goals(), len(robot.kb.plans()), len(robot.kb.events())) == stored
    alone = robot.dura("plan", "show", "--goal", asked[0])
    assert alone.returncode == 2 and "--goal goes with --dry-run" in alone.stderr


def test_a_timed_fact_is_planned_with_before_its_time_and_takes_effect_at_it(
    robot: Robot,
) -> None:
    asked = ("plan", "--dry-run", "--goal", "(picture_taken dock)", "--json")
    before = json.loads(robot.dura(*asked).stdout)
    assert before["status"] != "solved"  # nothing at the dock to photograph
    done = robot.dura("state", "set", "(photographable dock)", "--at", "+60")
    assert done.returncode == 0, done.stderr
    assert done.stdout.startswith("(photographable dock) from ") and " on" in done.stdout
    (timed,) = robot.kb.timed_facts()
    assert timed.fact == Fact("photographable", ("dock",))
    assert Fact("photographable", ("dock",)) not in robot.kb.facts()
    later = robot.dura("state", "get", "photographable").stdout.split("LATER")[1]
    assert "(photographable dock)" in later and "true" in later
    reply = json.loads(robot.dura(*asked).stdout)
    assert reply["status"] == "solved", reply
    (picture,) = [s for s in reply["steps"] if s["action"] == "take_picture"]
    assert picture["start"] >= 30.0  # once the dock has something to photograph (in 60 s)
    kinds = [(e.kind, e.subject) for e in robot.kb.events()]
    assert ("STATE_TIMED", "(photographable dock)") in kinds


def test_timed_facts_become_facts_of_the_world_when_their_time_comes(robot: Robot) -> None:
    # a few seconds ahead: each must still be to come when the executive hears of it
    assert robot.dura("state", "set", "(= (travel_time dock lab) 9)", "--at", "+6").returncode == 0
    assert robot.dura("state", "unset", "(photographable lab)", "--at", "+6").returncode == 0
    assert wait_for(lambda: not robot.kb.timed_facts(), 30)
    facts = robot.kb.facts()
    assert Fact("travel_time", ("dock", "lab"), 9.0) in facts
    assert Fact("photographable", ("lab",)) not in facts
    by_timed = [e for e in robot.kb.events() if e.data.get("source") == "timed"]
    assert {(e.kind, e.subject) for e in by_timed} == {
        ("STATE_SET", "(= (travel_time dock lab) 9)"),
        ("STATE_UNSET", "(not (photographable lab))"),
    }


@pytest.mark.parametrize(
    ("at", "error"),
    [
        ("2000-01-01T00:00", "2000-01-01T00:00 has passed: give a time to come"),
        ("soon", "'soon' is not a time: write 14:00, 14:00:30, +90"),
    ],
)
def test_a_time_that_is_not_to_come_is_a_usage_error(robot: Robot, at: str, error: str) -> None:
    done = robot.dura("state", "set", "(photographable dock)", "--at", at)
    assert done.returncode == 2
    assert error in done.stderr.splitlines()[-1]
    assert not robot.kb.timed_facts()


TAKEN = 6_000  # goals of a long run (a goal every 10 s for 17 hours): over 1 MB of goals
ENDS = ("achieved", "failed", "cancelled", "unreachable")


def taken(kb: KnowledgeBase, count: int) -> None:
    """``count`` goals that ended long ago, written in one transaction (as a long run
    leaves them; no event, so the goal planner has nothing to look at)."""
    with kb.transaction() as db:
        db.executemany(
            "INSERT INTO goals(expression, state, priority, deadline, source, reason,"
            " created, updated, keep) VALUES (?, ?, 0, NULL, 'user', ?, 1.0, 2.0, 0)",
            [("(picture_taken lab)", ENDS[n % 4], "a reason as a goal has one")
             for n in range(count)],
        )  # fmt: skip


def test_a_long_run_s_goals_are_listed_page_by_page_and_status_stays_bounded(
    robot: Robot,
) -> None:
    """Every goal ever taken no longer fits in one reply: ``goal/list`` sends the newest
    that fit and says there are more, a client pages through them all, and ``status``
    carries the open goals and the newest ended ones, with the count of each state."""
    taken(robot.kb, TAKEN)
    robot.runner.held.add("take_picture")
    running = json.loads(robot.dura("goal", "add", "(picture_taken office)", "--json").stdout)
    robot.runner.wait_for("take_picture(office)")
    every = list(range(1, TAKEN + 2))

    first = GOAL_LIST.call(robot.bus, GoalQuery())  # as a client before paging asks
    assert first.more and 0 < len(first.goals) < TAKEN
    assert [g.id for g in first.goals] == every[-len(first.goals) :]
    assert [g.id for g in newest_goals(robot.bus)] == every
    assert [g.id for g in newest_goals(robot.bus, 5)] == every[-5:]
    ended = newest_goals(robot.bus, 3, [GoalState.CANCELLED], before=TAKEN - 10)
    assert [g.state for g in ended] == [GoalState.CANCELLED] * 3 and ended[-1].id < TAKEN - 10

    assert [g.id for g in Client(robot).goals()] == every

    listed = robot.dura("goal", "list", "--json")
    assert listed.returncode == 0, listed.stderr
    assert [g["id"] for g in json.loads(listed.stdout)["goals"]] == every
    few = json.loads(robot.dura("goal", "list", "-n", "3", "--json").stdout)["goals"]
    assert [g["id"] for g in few] == every[-3:]
    table = robot.dura("goal", "list", "--lines", "2")
    assert table.returncode == 0 and len(table.stdout.splitlines()) == 3, table.stdout

    status = STATUS.call(robot.bus)
    assert [g.id for g in status.goals] == every[-RECENT_GOALS - 1 :]
    assert status.goals[-1].id == running["id"] and status.goals[-1].state.is_open
    assert status.goal_counts is not None and sum(status.goal_counts.values()) == TAKEN + 1
    assert status.goal_counts["cancelled"] == TAKEN // 4
    shown = robot.dura("status")
    assert shown.returncode == 0, shown.stderr
    assert (
        "take_picture(office)" in shown.stdout
        and f"{RECENT_GOALS + 1} of {TAKEN + 1}" in shown.stdout
    )
    assert len(shown.stdout.splitlines()) < 60, shown.stdout


def test_the_dashboard_shows_a_long_run_s_open_goals_and_the_newest_others(
    robot: Robot, endpoint: str
) -> None:
    taken(robot.kb, TAKEN)
    robot.runner.held.add("take_picture")
    running = json.loads(robot.dura("goal", "add", "(picture_taken office)", "--json").stdout)
    robot.runner.wait_for("take_picture(office)")
    for verb, reply in (  # the services the high level does not run: nothing to show
        (tasks.TASK_LIST, tasks.TasksReply([])),
        (tasks.SCHEDULE_SHOW, tasks.ScheduleReply([], [], [])),
        (components.COMPONENT_LIST, components.ComponentsReply([])),
        (monitoring.OBSERVER_LATEST, monitoring.LatestReply([])),
    ):
        verb.serve(robot.bus, lambda _, reply=reply: reply)  # type: ignore[misc]
    with Dashboard.connect(load_robot(USECASE), endpoint, port=0, folders=[]) as dashboard:
        shown = stream(dashboard, "goals", lambda data: bool(data["goals"]))["goals"]
    ids = [g["id"] for g in shown]
    assert ids == list(range(TAKEN + 2 - RECENT_SHOWN, TAKEN + 2))
    assert shown[-1]["id"] == running["id"] and shown[-1]["state"] == "executing"


class Client(RobotClient):
    """The test fixtures' client, on this bus."""

    def __init__(self, robot: Robot) -> None:
        self.robot = load_robot(USECASE)
        self._bus = robot.bus

    @property
    def bus(self) -> Bus:
        return self._bus
