"""The plan executor with a scripted task runner, a real knowledge base and real plans."""

from __future__ import annotations

import itertools
import threading
import time
from collections.abc import Callable, Iterator, Sequence

import pytest

from executive.bus.reports import StepStatus
from executive.planning.expression import Atom, Const
from executive.planning.goals import GoalSpec, submit
from executive.planning.partial_order import Effect, PartialOrderPlan, Step
from executive.planning.plan_executor import (
    ExecutionLimits,
    PlanExecutor,
    StepReport,
    StepTask,
)
from executive.planning.planner import Planner, PlanningTask
from executive.planning.problem import World
from executive.planning.state_change import Change, GoalChange, PlanChange
from knowledge.knowledge_base import KnowledgeBase
from knowledge.records import Fact, GoalState, PlanState
from tests.executive.planning.planning_cases import (
    USECASE_DOMAIN,
    expr,
    kairos_fixture,  # noqa: F401 (a fixture)
    usecase_domain,
    usecase_kb_fixture,  # noqa: F401 (a fixture)
)
from tests.executive.planning.scripted_runner import ScriptedRunner

TASKS = ("move_to", "take_picture")


def eventually(check: Callable[[], bool], timeout: float = 20.0) -> None:
    deadline = time.monotonic() + timeout
    while not check():
        if time.monotonic() > deadline:
            raise AssertionError("condition not met in time")
        time.sleep(0.01)


class Run:
    """An executor on the use-case KB, with the replan requests it made."""

    def __init__(self, kb: KnowledgeBase, runner: ScriptedRunner, **options: object) -> None:
        self.kb = kb
        self.runner = runner
        self.replans: list[str] = []
        tasks = options.pop("tasks", TASKS)
        self.executor = PlanExecutor(kb, runner, tasks, self.replans.append, **options)  # type: ignore[arg-type]
        self.executor.start()

    def plan(self, kairos: Planner, *goals: str) -> tuple[PartialOrderPlan, int, list[GoalSpec]]:
        domain = usecase_domain()
        specs = [GoalSpec(submit(self.kb, domain, g).id, expr(g)) for g in goals]
        world = World(self.kb.objects(), tuple(self.executor.planning_facts()))
        result = kairos.solve(PlanningTask(USECASE_DOMAIN, world, tuple(specs)))
        assert result.plan is not None, result.log
        stored = self.kb.store_plan(
            result.plan.records(), engine="kairos", goal_ids=[g.id for g in specs]
        )
        for spec in specs:  # as the goal planner does before it hands a plan over
            self.kb.set_goal_state(spec.id, GoalState.PLANNED)
        return result.plan, stored.id, specs

    def execute(self, kairos: Planner, *goals: str) -> tuple[PartialOrderPlan, int, list[GoalSpec]]:
        """Plan for goals and run the plan."""
        plan, plan_id, specs = self.plan(kairos, *goals)
        self.executor.execute(plan, plan_id, specs)
        return plan, plan_id, specs

    def kinds(self) -> list[tuple[str, str]]:
        return [
            (e.kind, e.subject)
            for e in self.kb.events()
            if e.kind in ("DISPATCH", "START", "END", "FAIL", "CANCEL", "REPLAN")
        ]


@pytest.fixture
def run(usecase_kb: KnowledgeBase) -> Iterator[Callable[..., Run]]:
    made: list[Run] = []

    def make(runner: ScriptedRunner | None = None, **options: object) -> Run:
        r = Run(usecase_kb, runner or ScriptedRunner(), **options)
        made.append(r)
        return r

    yield make
    for r in made:
        r.executor.stop()


def test_steps_run_in_order_their_effects_change_the_facts_and_the_goals_are_achieved(
    run: Callable[..., Run], kairos: Planner
) -> None:
    r = run()
    plan, plan_id, _goals = r.execute(kairos, "(picture_taken lab)", "(robot_at office)")
    eventually(lambda: r.kb.plan(plan_id).state is PlanState.SUCCEEDED)
    assert [g.state for g in r.kb.goals()] == [GoalState.ACHIEVED, GoalState.ACHIEVED]
    facts = r.kb.facts()
    assert Fact("picture_taken", ("lab",)) in facts
    assert Fact("robot_at", ("office",)) in facts
    assert Fact("robot_at", ("dock",)) not in facts
    kinds = r.kinds()
    labels = [s.label for s in plan.steps]
    assert kinds == [(k, label) for label in labels for k in ("DISPATCH", "START", "END")]
    assert r.replans == []
    assert [e.kind for e in r.kb.events(kind="PLAN_START")] == ["PLAN_START"]


def test_a_failed_step_asks_for_a_new_plan_with_the_reason(
    run: Callable[..., Run], kairos: Planner
) -> None:
    r = run(ScriptedRunner(fail={"take_picture(lab)": "the camera is faulty"}))
    _plan, plan_id, goals = r.execute(kairos, "(picture_taken lab)")
    eventually(lambda: bool(r.replans))
    assert r.replans == ["step take_picture(lab) failed: the camera is faulty"]
    plan_record = r.kb.plan(plan_id)
    assert plan_record.state is PlanState.FAILED
    assert ("FAIL", "take_picture(lab)") in r.kinds()
    assert r.kb.goal(goals[0].id).state is GoalState.EXECUTING


def test_a_running_step_whose_over_all_condition_breaks_fails(
    run: Callable[..., Run], kairos: Planner
) -> None:
    runner = ScriptedRunner(held={"move_to"})
    r = run(runner)
    _plan, _plan_id, _goals = r.execute(kairos, "(robot_at lab)")
    task = runner.wait_for("move_to(dock, lab)")
    r.kb.unset_fact(Fact("connected", ("dock", "lab")))
    r.executor.facts_changed()
    eventually(lambda: bool(r.replans))
    assert r.replans == ["over-all condition (connected dock lab) no longer holds"]
    assert task.calls == ["cancel"]


def test_a_step_running_past_its_duration_and_the_margin_times_out(
    run: Callable[..., Run],
) -> None:
    runner = ScriptedRunner(held={"move_to"})
    r = run(runner, limits=ExecutionLimits(margin=0.2, relative=0.0))
    step = Step(0, "move_to", ("dock", "lab"), ("from", "to"), 0.0, 0.1,
                at_start=Atom("robot_at", ("dock",)))  # fmt: skip
    plan_id = r.kb.store_plan(PartialOrderPlan((step,)).records()).id
    r.executor.execute(PartialOrderPlan((step,)), plan_id, [])
    eventually(lambda: bool(r.replans))
    assert r.replans == [
        "step move_to(dock, lab) timed out: still running after 0.3 s (expected 0.1 s)"
    ]
    assert runner.wait_for("move_to(dock, lab)").calls == ["cancel"]


def test_pausing_pauses_interruptible_tasks_and_waits_for_critical_ones(
    run: Callable[..., Run], kairos: Planner
) -> None:
    runner = ScriptedRunner(held={"move_to", "take_picture"}, critical={"take_picture"})
    r = run(runner)
    _, plan_id, _ = r.execute(kairos, "(robot_at lab)")
    move = runner.wait_for("move_to(dock, lab)")
    assert r.executor.pause(timeout=10)
    assert move.calls == ["pause"]
    status = r.executor.status()
    assert (status.plan, status.paused) == (plan_id, True)
    assert [s.state for s in status.steps] == ["paused"]
    # the planner sees the robot where the paused step started
    assert Fact("robot_at", ("dock",)) in r.executor.planning_facts()
    assert Fact("robot_at", ("dock",)) not in r.kb.facts()
    r.executor.resume()
    assert move.calls == ["pause", "resume"]
    move.end(None)
    eventually(lambda: r.kb.plan(plan_id).state is PlanState.SUCCEEDED)

    _plan, plan_id, _goals = r.execute(kairos, "(picture_taken lab)")
    picture = runner.wait_for("take_picture(lab)")
    assert not r.executor.pause(timeout=0.3)  # a critical task is not interrupted
    assert picture.calls == []
    picture.end(None)
    assert r.executor.pause(timeout=10)
    assert r.kb.plan(plan_id).state is PlanState.SUCCEEDED


def test_a_new_plan_continues_a_paused_task_that_is_its_first_step_and_cancels_the_rest(
    run: Callable[..., Run], kairos: Planner
) -> None:
    runner = ScriptedRunner(held={"move_to"})
    r = run(runner)
    _plan, _plan_id, _goals = r.execute(kairos, "(robot_at lab)")
    move = runner.wait_for("move_to(dock, lab)")
    assert r.executor.pause(timeout=10)
    # replanned for the same goal: the same first step continues
    _plan2, plan2_id, _goals2 = r.execute(kairos, "(robot_at lab)")
    assert move.calls == ["pause", "resume"]
    move.end(None)
    eventually(lambda: r.kb.plan(plan2_id).state is PlanState.SUCCEEDED)
    assert len(runner.tasks) == 1

    # now a plan that starts elsewhere: the paused step is cancelled and undone
    plan3, _plan3_id, _goals3 = r.execute(kairos, "(robot_at office)")
    first = runner.wait_for(plan3.steps[0].label)
    assert r.executor.pause(timeout=10)
    plan4 = PartialOrderPlan(())
    r.executor.execute(plan4, r.kb.store_plan(()).id, [])
    assert first.calls == ["pause", "cancel"]
    assert Fact("robot_at", ("lab",)) in r.kb.facts()  # its at-start effect was undone
    assert ("CANCEL", plan3.steps[0].label) in r.kinds()


def test_an_action_without_a_task_completes_at_once_with_its_effects(
    run: Callable[..., Run],
) -> None:
    r = run(tasks=())
    step = Step(0, "move_to", ("dock", "lab"), ("from", "to"), 0.0, 4.0,
                at_start=Atom("robot_at", ("dock",)),
                start_effects=(Effect("robot_at", ("dock",), Const(False)),),
                end_effects=(Effect("robot_at", ("lab",), Const(True)),))  # fmt: skip
    plan_id = r.kb.store_plan(PartialOrderPlan((step,)).records()).id
    r.executor.execute(PartialOrderPlan((step,)), plan_id, [])
    eventually(lambda: r.kb.plan(plan_id).state is PlanState.SUCCEEDED)
    assert r.runner.tasks == []
    assert Fact("robot_at", ("lab",)) in r.kb.facts()


def test_a_step_that_cannot_start_makes_the_plan_fail(
    run: Callable[..., Run], kairos: Planner
) -> None:
    r = run()
    plan, plan_id, goals = r.plan(kairos, "(robot_at lab)")
    r.kb.update_facts(remove=[Fact("robot_at", ("dock",))], add=[Fact("robot_at", ("office",))])
    r.executor.execute(plan, plan_id, goals)
    eventually(lambda: bool(r.replans))
    assert r.replans == ["step move_to(dock, lab) cannot start: (robot_at dock) does not hold"]
    assert r.runner.tasks == []


class Blocking(ScriptedRunner):
    """A runner whose ``run`` does not return until released (a slow task executor)."""

    def __init__(self) -> None:
        super().__init__()
        self.entered = threading.Event()
        self.release = threading.Event()

    def run(self, step: Step, plan_id: int, report: StepReport) -> StepTask:
        self.entered.set()
        self.release.wait(30)
        return super().run(step, plan_id, report)


def test_status_answers_from_a_snapshot_while_the_executor_is_busy(
    run: Callable[..., Run], kairos: Planner
) -> None:
    runner = Blocking()
    r = run(runner)
    plan, plan_id, goals = r.plan(kairos, "(robot_at lab)")
    handing_over = threading.Thread(target=r.executor.execute, args=(plan, plan_id, goals))
    handing_over.start()
    try:
        assert runner.entered.wait(10)  # the executor's thread waits in the runner
        status = r.executor.status()  # answered while its thread is held in the runner
        assert status.plan is None  # as of the last job: the plan is not handed over yet
    finally:
        runner.release.set()
        handing_over.join(10)
    eventually(lambda: r.executor.status().plan == plan_id)
    eventually(lambda: r.kb.plan(plan_id).state is PlanState.SUCCEEDED)
    # the snapshot follows the job that ended the plan (it is taken after each job)
    eventually(lambda: r.executor.status().steps == (StepStatus(0, "move_to(dock, lab)", "ended"),))


def test_an_executor_with_an_owner_reports_goal_and_plan_changes_instead_of_writing_them(
    run: Callable[..., Run], kairos: Planner
) -> None:
    r = run()
    told: list[Change] = []
    r.executor.report_to(told.append)
    _plan, plan_id, goals = r.execute(kairos, "(robot_at lab)")
    eventually(lambda: PlanChange(plan_id, PlanState.SUCCEEDED) in told)
    goal = goals[0].id
    assert told == [
        PlanChange(plan_id, PlanState.EXECUTING),
        GoalChange(goal, GoalState.EXECUTING),
        GoalChange(goal, GoalState.ACHIEVED),
        PlanChange(plan_id, PlanState.SUCCEEDED),
    ]
    assert r.kb.goal(goal).state is GoalState.PLANNED  # the owner had not applied them
    assert r.kb.plan(plan_id).state is PlanState.PENDING


class TellingRunner(ScriptedRunner):
    """A scripted runner that keeps what it was told of the steps to come."""

    def __init__(self) -> None:
        super().__init__()
        self.told: list[tuple[int | None, list[str]]] = []

    def upcoming(self, plan_id: int | None, steps: Sequence[Step]) -> None:
        self.told.append((plan_id, [s.label for s in steps]))


def test_the_runner_is_told_the_steps_still_to_come_until_the_plan_ends(
    run: Callable[..., Run], kairos: Planner
) -> None:
    runner = TellingRunner()
    r = run(runner)
    plan, plan_id, _goals = r.execute(kairos, "(picture_taken lab)", "(robot_at office)")
    eventually(lambda: r.kb.plan(plan_id).state is PlanState.SUCCEEDED)
    eventually(lambda: runner.told[-1] == (plan_id, []))
    first = min(plan.steps, key=lambda s: s.start).label
    told = [set(steps) for told_plan, steps in runner.told if told_plan == plan_id]
    assert told[0] == {s.label for s in plan.steps} - {first}  # the first one is under way
    assert all(later < earlier for earlier, later in itertools.pairwise(told))
