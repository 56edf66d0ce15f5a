"""The goal planner with a real planner, the plan executor and a scripted task runner."""

from __future__ import annotations

import os
import threading
from collections.abc import Callable, Iterator
from pathlib import Path

import pytest

from executive.bus.reports import RoundPhase
from executive.planning.goal_planner import GoalPlanner
from executive.planning.goals import submit
from executive.planning.partial_order import Step
from executive.planning.plan_executor import PlanExecutor, StepReport, StepTask
from executive.planning.planner import Planner
from knowledge.errors import KnowledgeError
from knowledge.knowledge_base import KnowledgeBase
from knowledge.records import Goal, GoalState
from tests.conftest import ROOT
from tests.executive.planning import slow_engine
from tests.executive.planning.planning_cases import (
    USECASE_DOMAIN,
    kairos_fixture,  # noqa: F401 (a fixture)
    usecase_domain,
    usecase_kb_fixture,  # noqa: F401 (a fixture)
)
from tests.executive.planning.scripted_runner import ScriptedRunner
from tests.executive.planning.test_plan_executor import TASKS, eventually


class Executive:
    """The high level of an executive: goal planner and plan executor on one KB."""

    def __init__(
        self,
        kb: KnowledgeBase,
        planner: Planner,
        runner: ScriptedRunner,
        attempts: int = 5,
        blocked: dict[str, str] | None = None,
    ) -> None:
        self.kb = kb
        self.runner = runner
        self.blocked = dict(blocked or {})
        self.executor = PlanExecutor(kb, runner, TASKS, self._replan)
        self.goals = GoalPlanner(
            kb,
            usecase_domain(),
            planner,
            self.executor,
            max_attempts=attempts,
            blocked=lambda: self.blocked,
        )
        self.executor.start()
        self.goals.start()

    def _replan(self, reason: str) -> None:
        self.goals.replan(reason)

    def submit(self, text: str, **options: object) -> Goal:
        goal = submit(self.kb, usecase_domain(), text, **options)  # type: ignore[arg-type]
        self.goals.wake(f"goal {goal.id} added")
        return goal

    def state(self, goal: Goal) -> GoalState:
        return self.kb.goal(goal.id).state

    def settled(self) -> bool:
        return not self.kb.open_goals()

    def stop(self) -> None:
        self.goals.stop()
        self.executor.stop()


@pytest.fixture
def executive(usecase_kb: KnowledgeBase, kairos: Planner) -> Iterator[Callable[..., Executive]]:
    made: list[Executive] = []

    def make(
        runner: ScriptedRunner | None = None,
        attempts: int = 5,
        blocked: dict[str, str] | None = None,
    ) -> Executive:
        e = Executive(usecase_kb, kairos, runner or ScriptedRunner(), attempts, blocked)
        made.append(e)
        return e

    yield make
    for e in made:
        e.stop()


def test_submitted_goals_are_planned_executed_and_achieved(
    executive: Callable[..., Executive],
) -> None:
    ex = executive()
    pictures = ex.submit("(and (picture_taken lab) (picture_taken office))")
    there = ex.submit("(robot_at lab)")
    eventually(ex.settled)
    assert ex.state(pictures) is GoalState.ACHIEVED
    assert ex.state(there) is GoalState.ACHIEVED
    assert ("robot_at", ("lab",)) in {(f.name, f.args) for f in ex.kb.facts()}


def test_a_task_failure_leads_to_replanning_and_success(
    executive: Callable[..., Executive],
) -> None:
    ex = executive(ScriptedRunner(fail={"take_picture(lab)": "the camera froze"}))
    goal = ex.submit("(picture_taken lab)")
    eventually(ex.settled)
    assert ex.state(goal) is GoalState.ACHIEVED
    assert ex.runner.labels().count("take_picture(lab)") == 2
    replans = [e.data["reason"] for e in ex.kb.events(kind="REPLAN")]
    assert replans == ["step take_picture(lab) failed: the camera froze"]
    assert len(ex.kb.plans()) == 2


def test_an_unreachable_goal_is_reported_with_a_reason_while_the_others_are_achieved(
    executive: Callable[..., Executive],
) -> None:
    ex = executive()
    lab = ex.submit("(picture_taken lab)", priority=2)
    dock = ex.submit("(picture_taken dock)", priority=5)
    eventually(ex.settled)
    assert ex.state(lab) is GoalState.ACHIEVED
    record = ex.kb.goal(dock.id)
    assert record.state is GoalState.UNREACHABLE
    assert record.reason.startswith("no plan reaches it from the current state")
    assert [e.subject for e in ex.kb.events(kind="GOAL_UNREACHABLE")] == [f"goal {dock.id}"]


def test_a_goal_that_needs_a_task_which_cannot_run_is_unreachable_with_the_reason(
    executive: Callable[..., Executive],
) -> None:
    ex = executive(blocked={"take_picture": "behavior take_picture is permanently faulty"})
    picture = ex.submit("(picture_taken lab)", priority=5)
    there = ex.submit("(robot_at lab)")
    eventually(ex.settled)
    assert ex.state(there) is GoalState.ACHIEVED
    record = ex.kb.goal(picture.id)
    assert record.state is GoalState.UNREACHABLE
    assert record.reason.endswith(
        "; cannot run now: take_picture (behavior take_picture is permanently faulty)"
    )
    assert "take_picture(lab)" not in ex.runner.labels()
    assert ex.kb.events(kind="PLANNING")[-1].data["blocked"] == ["take_picture"]
    # the task can run again (a reset after maintenance): a new goal for it is planned
    ex.blocked.clear()
    again = ex.submit("(picture_taken lab)")
    eventually(ex.settled)
    assert ex.state(again) is GoalState.ACHIEVED


def test_a_critical_task_is_not_interrupted_by_replanning(
    executive: Callable[..., Executive],
) -> None:
    runner = ScriptedRunner(held={"take_picture"}, critical={"take_picture"})
    ex = executive(runner)
    lab = ex.submit("(picture_taken lab)")
    picture = runner.wait_for("take_picture(lab)")
    office = ex.submit("(picture_taken office)")
    eventually(lambda: ex.kb.events(kind="PLANNING")[-1].data["goals"] == [lab.id, office.id])
    assert picture.calls == []  # asked to pause? no: it is critical, the planner waits
    assert len(ex.kb.plans()) == 1
    picture.end(None)
    picture_office = runner.wait_for("take_picture(office)")
    picture_office.end(None)
    eventually(ex.settled)
    assert picture.calls == []
    assert ex.state(lab) is GoalState.ACHIEVED and ex.state(office) is GoalState.ACHIEVED


def test_a_restarted_goal_planner_continues_the_open_goals_from_the_kb(
    executive: Callable[..., Executive],
) -> None:
    runner = ScriptedRunner(held={"take_picture"})
    first = executive(runner)
    goal = first.submit("(picture_taken office)")
    runner.wait_for("take_picture(office)")
    first.stop()  # the executive dies with its goal open
    assert first.state(goal).is_open
    second = executive()
    eventually(second.settled)
    assert second.state(goal) is GoalState.ACHIEVED
    assert "take_picture(office)" in second.runner.labels()


def test_a_goal_that_already_holds_is_achieved_without_a_plan(
    executive: Callable[..., Executive],
) -> None:
    ex = executive()
    goal = ex.submit("(robot_at dock)")
    eventually(ex.settled)
    assert ex.state(goal) is GoalState.ACHIEVED
    assert ex.kb.plans() == []
    assert ex.runner.tasks == []


def test_a_cancelled_goal_is_no_longer_pursued(executive: Callable[..., Executive]) -> None:
    runner = ScriptedRunner(held={"move_to"})
    ex = executive(runner)
    goal = ex.submit("(robot_at office)")
    move = runner.wait_for("move_to(dock, office)")
    ex.goals.cancel(goal.id)
    eventually(lambda: "cancel" in move.calls)
    assert ex.state(goal) is GoalState.CANCELLED
    assert ("robot_at", ("dock",)) in {(f.name, f.args) for f in ex.kb.facts()}


class AlwaysFailing(ScriptedRunner):
    """Every take_picture fails (the camera is broken for good)."""

    def run(self, step: Step, plan_id: int, report: StepReport) -> StepTask:
        if step.action == "take_picture":
            self.fail_once[step.label] = "the camera is broken"
        return super().run(step, plan_id, report)


def test_a_goal_fails_once_its_plans_failed_too_often(
    executive: Callable[..., Executive],
) -> None:
    ex = executive(AlwaysFailing(), attempts=2)
    picture = ex.submit("(picture_taken lab)")
    eventually(ex.settled)
    record = ex.kb.goal(picture.id)
    assert record.state is GoalState.FAILED
    assert record.reason.startswith("2 plans for it failed, the last because step take_picture")
    assert len(ex.kb.plans()) == 2


@pytest.fixture
def slow_kairos(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Iterator[Planner]:
    """Kairos as a plugin that takes 2 s for every plan (tests/executive/planning/slow_engine.py)."""
    plugins = slow_engine.register(tmp_path / "plugins")
    monkeypatch.syspath_prepend(str(plugins))
    monkeypatch.setenv("PYTHONPATH", os.pathsep.join((str(plugins), str(ROOT))))
    with Planner(slow_engine.NAME, timeout=10.0) as planner:
        planner.start(USECASE_DOMAIN)
        yield planner


def test_a_goal_cancelled_during_the_search_is_cancelled_at_once_and_never_planned(
    usecase_kb: KnowledgeBase, slow_kairos: Planner
) -> None:
    ex = Executive(usecase_kb, slow_kairos, ScriptedRunner())
    try:
        with ex.kb.transaction():  # both goals in the same round
            office = submit(ex.kb, usecase_domain(), "(picture_taken office)", priority=5)
            lab = submit(ex.kb, usecase_domain(), "(robot_at lab)")
        ex.goals.wake("two goals added")
        eventually(lambda: ex.goals.status().phase is RoundPhase.SEARCHING)

        cancelled = ex.goals.cancel(office.id)

        assert cancelled.state is GoalState.CANCELLED
        # the cancel was applied while the search still ran: the owner did not wait for it
        assert ex.goals.status().phase is RoundPhase.SEARCHING
        eventually(lambda: ex.state(lab) is GoalState.ACHIEVED)
        first, again = ex.kb.events(kind="PLANNING")
        assert first.data["goals"] == [office.id, lab.id]
        assert again.data == {
            "reason": f"goals {office.id} cancelled while planning",
            "goals": [lab.id],
            "blocked": [],
        }
        assert again.stamp - first.stamp >= slow_engine.THINK
        assert ex.state(office) is GoalState.CANCELLED
        history = [e.kind for e in ex.kb.events() if e.subject == f"goal {office.id}"]
        assert history == ["GOAL_ADDED", "GOAL_CANCELLED"]
        assert [p.goal_ids for p in ex.kb.plans()] == [(lab.id,)]
        assert ex.runner.labels() == ["move_to(dock, lab)"]
        assert [e.data["goals"] for e in ex.kb.events(kind="PLAN_START")] == [[lab.id]]
        eventually(lambda: not ex.goals.status().planning)
        print(f"search with the cancel: {again.stamp - first.stamp:.2f} s")
    finally:
        ex.stop()


def test_a_cancelled_goal_stays_cancelled_and_a_second_cancel_says_so(
    executive: Callable[..., Executive],
) -> None:
    ex = executive(ScriptedRunner(held={"move_to"}))
    goal = ex.submit("(robot_at office)")
    ex.runner.wait_for("move_to(dock, office)")
    assert ex.goals.cancel(goal.id).state is GoalState.CANCELLED
    with pytest.raises(KnowledgeError, match=f"^goal {goal.id} is cancelled already$"):
        ex.goals.cancel(goal.id)
    with pytest.raises(KnowledgeError, match=r"^no goal 99$"):
        ex.goals.cancel(99)
    eventually(lambda: not ex.goals.status().planning)
    assert ex.state(goal) is GoalState.CANCELLED
    kinds = [e.kind for e in ex.kb.events() if e.subject == f"goal {goal.id}"]
    assert kinds[-1] == "GOAL_CANCELLED" and kinds.count("GOAL_CANCELLED") == 1


def test_the_executor_reports_and_the_goal_planner_writes_every_goal_state(
    executive: Callable[..., Executive],
) -> None:
    ex = executive()
    writers: list[str] = []
    original = ex.kb.set_goal_state

    def set_goal_state(goal_id: int, state: GoalState, reason: str = "") -> Goal:
        writers.append(threading.current_thread().name)
        return original(goal_id, state, reason)

    ex.kb.set_goal_state = set_goal_state  # type: ignore[method-assign]
    goal = ex.submit("(picture_taken lab)")
    eventually(ex.settled)
    assert ex.state(goal) is GoalState.ACHIEVED
    kinds = [e.kind for e in ex.kb.events() if e.subject == f"goal {goal.id}"]
    assert kinds == ["GOAL_ADDED", "GOAL_PLANNED", "GOAL_EXECUTING", "GOAL_ACHIEVED"]
    assert set(writers) == {"goal planner"}


READING = "(battery_level) = 93 set by base"  # a sensor's reading: a wake-up, no reason to plan


def test_a_goal_achieved_leaves_the_plan_to_the_others_and_a_reading_does_not_replace_it(
    executive: Callable[..., Executive],
) -> None:
    runner = ScriptedRunner(held={"take_picture"})
    ex = executive(runner)
    with ex.kb.transaction():  # both goals in the same round
        lab = submit(ex.kb, usecase_domain(), "(picture_taken lab)")
        office = submit(ex.kb, usecase_domain(), "(picture_taken office)")
    ex.goals.wake("two goals added")
    eventually(lambda: "take_picture" in {t.step.action for t in runner.tasks})
    first = runner.tasks[-1]  # the planner picks the order
    first.end(None)
    done, other = (lab, office) if first.step.args == ("lab",) else (office, lab)
    eventually(lambda: ex.state(done) is GoalState.ACHIEVED)
    second = runner.wait_for(f"take_picture({'office' if other is office else 'lab'})")
    ex.goals.wake(READING)
    second.end(None)
    eventually(ex.settled)  # written on the goal planner's thread, after the reading
    assert ex.state(other) is GoalState.ACHIEVED
    (planning,) = ex.kb.events(kind="PLANNING")
    assert set(planning.data["reason"].split("; ")) <= {
        "the executive started",
        f"goal {lab.id} added",
        f"goal {office.id} added",
    }
    assert [p.goal_ids for p in ex.kb.plans()] == [(lab.id, office.id)]
    assert ex.goals.status().planned == ()


def test_a_round_names_the_goal_that_changed_not_the_wake_up_that_came_first(
    executive: Callable[..., Executive],
) -> None:
    runner = ScriptedRunner(held={"take_picture"})
    ex = executive(runner)
    lab = ex.submit("(picture_taken lab)")
    picture = runner.wait_for("take_picture(lab)")
    # a goal stored, and a reading wakes the goal planner before the goal's own wake-up
    office = submit(ex.kb, usecase_domain(), "(picture_taken office)")
    ex.goals.wake(READING)
    eventually(lambda: len(ex.kb.events(kind="PLANNING")) == 2)
    assert ex.kb.events(kind="PLANNING")[-1].data["reason"] == f"goal {office.id} added"
    picture.end(None)
    runner.wait_for("take_picture(office)").end(None)
    eventually(ex.settled)
    assert ex.state(lab) is GoalState.ACHIEVED and ex.state(office) is GoalState.ACHIEVED
