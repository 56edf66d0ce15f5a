"""The goal planner with a real planner, the plan executer and a scripted task runner."""

from __future__ import annotations

from collections.abc import Callable, Iterator

import pytest

from executive.planning.goal_planner import GoalPlanner
from executive.planning.goals import submit
from executive.planning.partial_order import Step
from executive.planning.plan_executer import PlanExecuter, StepReport, StepTask
from executive.planning.planner import Planner
from knowledge.knowledge_base import KnowledgeBase
from knowledge.records import Goal, GoalState
from tests.executive.planning.planning_cases import (
    kairos_fixture,  # noqa: F401 (a fixture)
    usecase_domain,
    usecase_kb_fixture,  # noqa: F401 (a fixture)
)
from tests.executive.planning.scripted_runner import ScriptedRunner
from tests.executive.planning.test_plan_executer import TASKS, eventually


class Executive:
    """The high level of an executive: goal planner and plan executer on one KB."""

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
        self.executer = PlanExecuter(kb, runner, TASKS, self._replan)
        self.goals = GoalPlanner(
            kb,
            usecase_domain(),
            planner,
            self.executer,
            max_attempts=attempts,
            blocked=lambda: self.blocked,
        )
        self.executer.start()
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
        self.executer.stop()


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
