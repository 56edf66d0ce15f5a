"""Recovery after a crash: the plan executor on a real knowledge base, "killed" by
copying the committed database at a chosen moment, and the copy recovered as a
restarted executive recovers it.

The plans are written by hand (the use-case actions with their effects), so that each
test knows which step runs when a replan replaces the plan.
"""

from __future__ import annotations

import sqlite3
import time
from collections.abc import Callable, Iterator
from pathlib import Path

import pytest

from executive.planning.expression import Atom, Const, conjunction
from executive.planning.partial_order import (
    Effect,
    PartialOrderPlan,
    Precedence,
    Step,
    Timepoint,
)
from executive.planning.plan_executor import PlanExecutor, StepReport, StepTask
from executive.planning.recovery import recover
from knowledge.knowledge_base import KnowledgeBase
from knowledge.records import Event, Fact
from tests.executive.planning.planning_cases import usecase_kb_fixture  # noqa: F401 (a fixture)
from tests.executive.planning.scripted_runner import ScriptedRunner, ScriptedTask

STEP_ENDS = ("END", "FAIL", "CANCEL")


def move(index: int, there: str, to: str, *after: Precedence) -> Step:
    """``move_to`` as the use-case domain has it."""
    return Step(
        index, "move_to", (there, to), ("from", "to"), 0.0, 4.0, after=after,
        at_start=Atom("robot_at", (there,)), over_all=Atom("connected", (there, to)),
        start_effects=(Effect("robot_at", (there,), Const(False)),),
        end_effects=(Effect("robot_at", (to,), Const(True)),),
    )  # fmt: skip


def picture(index: int, place: str, *after: Precedence) -> Step:
    """``take_picture`` as the use-case domain has it."""
    return Step(
        index, "take_picture", (place,), ("p",), 4.0, 2.0, after=after,
        at_start=conjunction([Atom("photographable", (place,)), Atom("robot_at", (place,))]),
        over_all=Atom("robot_at", (place,)),
        end_effects=(Effect("picture_taken", (place,), Const(True)),),
    )  # fmt: skip


def ended(step: int) -> Precedence:
    return Precedence(step, Timepoint.END)


def eventually(check: Callable[[], bool], timeout: float = 20.0) -> None:
    deadline = time.monotonic() + timeout
    while not check():
        if time.monotonic() > deadline:
            raise AssertionError("condition not met in time")
        time.sleep(0.01)


def crashed(kb: KnowledgeBase, folder: Path) -> KnowledgeBase:
    """What an executive killed now leaves behind: the committed state of ``kb``,
    copied, with the restarted executive's EXECUTIVE_STARTED logged."""
    copy = folder / f"after-crash-{time.monotonic_ns()}.db"
    with sqlite3.connect(kb.path) as source, sqlite3.connect(copy) as target:
        source.backup(target)
    restarted = KnowledgeBase(copy)
    restarted.log_event("EXECUTIVE_STARTED", "usecase")
    return restarted


def places(kb: KnowledgeBase) -> list[str]:
    return [f.args[0] for f in kb.facts("robot_at")]


def logged(kb: KnowledgeBase, kind: str, label: str) -> list[Event]:
    return [e for e in kb.events(kind=kind) if e.subject == label]


class Executor:
    """A plan executor on the use-case KB whose ``move_to`` steps wait to be finished."""

    def __init__(self, kb: KnowledgeBase) -> None:
        self.kb = kb
        kb.log_event("EXECUTIVE_STARTED", "usecase")  # as the executive does first
        self.runner = ScriptedRunner(held={"move_to"})
        self.replans: list[str] = []
        self.executor = PlanExecutor(
            kb, self.runner, ("move_to", "take_picture"), self.replans.append
        )
        self.executor.start()

    def execute(self, *steps: Step) -> int:
        plan = PartialOrderPlan(steps)
        plan_id = self.kb.store_plan(plan.records()).id
        self.executor.execute(plan, plan_id, [])
        return plan_id

    def started(self, label: str, count: int = 1) -> None:
        eventually(lambda: len(logged(self.kb, "START", label)) >= count)


@pytest.fixture
def executor(usecase_kb: KnowledgeBase) -> Iterator[Executor]:
    made = Executor(usecase_kb)
    yield made
    made.executor.stop()


def test_a_step_adopted_by_a_new_plan_and_ended_is_not_undone_after_a_crash(
    executor: Executor, tmp_path: Path
) -> None:
    """The issue's robot in two places: plan 2 continues plan 1's drive to the lab,
    which ends; the crash comes while plan 2 drives on to the office."""
    executor.execute(move(0, "dock", "lab"), picture(1, "lab", ended(0)))
    executor.started("move_to(dock, lab)")
    assert executor.executor.pause(timeout=10)
    executor.execute(
        move(0, "dock", "lab"), picture(1, "lab", ended(0)), move(2, "lab", "office", ended(1))
    )
    executor.runner.wait_for("move_to(dock, lab)").end(None)
    executor.started("move_to(lab, office)")

    kb = crashed(executor.kb, tmp_path)
    assert recover(kb) == ["move_to(lab, office)"]

    assert places(kb) == ["lab"]  # where the finished steps left the robot
    assert Fact("picture_taken", ("lab",)) in kb.facts()
    assert len(logged(kb, "CANCEL", "move_to(dock, lab)")) == 0
    assert len(logged(kb, "CANCEL", "move_to(lab, office)")) == 1


def test_a_step_the_new_plan_cancels_is_undone_once_and_logged_with_its_own_plan(
    executor: Executor, tmp_path: Path
) -> None:
    first = executor.execute(move(0, "dock", "lab"))
    executor.started("move_to(dock, lab)")
    assert executor.executor.pause(timeout=10)
    second = executor.execute(move(0, "dock", "office"))
    executor.started("move_to(dock, office)")
    (cancel,) = logged(executor.kb, "CANCEL", "move_to(dock, lab)")
    assert cancel.data["plan"] == first

    kb = crashed(executor.kb, tmp_path)
    assert recover(kb) == ["move_to(dock, office)"]

    assert places(kb) == ["dock"]
    assert len(logged(kb, "CANCEL", "move_to(dock, lab)")) == 1  # not undone a second time
    (died,) = logged(kb, "CANCEL", "move_to(dock, office)")
    assert (died.data["plan"], died.data["reason"]) == (second, "the executive died")


def test_every_event_of_a_step_run_names_the_run_whatever_plan_continues_it(
    executor: Executor,
) -> None:
    executor.execute(move(0, "dock", "lab"))
    executor.started("move_to(dock, lab)")
    assert executor.executor.pause(timeout=10)
    executor.execute(picture(0, "lab"), move(1, "dock", "lab", ended(0)))
    # the drive is not a first step of plan 2: it is cancelled ...
    eventually(lambda: bool(logged(executor.kb, "CANCEL", "move_to(dock, lab)")))
    third = executor.execute(move(0, "dock", "lab"))  # ... and run again, then adopted
    executor.started("move_to(dock, lab)", count=2)
    assert executor.executor.pause(timeout=10)
    fourth = executor.execute(move(0, "dock", "lab"), picture(1, "lab", ended(0)))
    executor.runner.wait_for("move_to(dock, lab)").end(None)
    eventually(lambda: bool(logged(executor.kb, "END", "move_to(dock, lab)")))

    runs: dict[int, list[str]] = {}
    for e in executor.kb.events():
        if e.subject == "move_to(dock, lab)":
            run = e.id if e.kind == "DISPATCH" else e.data["run"]
            runs.setdefault(run, []).append(e.kind)
    assert list(runs.values()) == [
        ["DISPATCH", "START", "CANCEL"],
        ["DISPATCH", "START", "ADOPT", "END"],
    ]
    (adopt,) = logged(executor.kb, "ADOPT", "move_to(dock, lab)")
    assert (adopt.data["from_plan"], adopt.data["plan"]) == (third, fourth)
    (end,) = logged(executor.kb, "END", "move_to(dock, lab)")
    assert end.data["plan"] == fourth


def test_an_executive_killed_before_it_recovered_leaves_the_recovery_to_the_next(
    executor: Executor, tmp_path: Path
) -> None:
    executor.execute(move(0, "dock", "lab"))
    executor.started("move_to(dock, lab)")

    kb = crashed(executor.kb, tmp_path)  # the second executive dies before it recovers
    kb.log_event("EXECUTIVE_STARTED", "usecase")  # and a third one starts

    assert recover(kb) == ["move_to(dock, lab)"]
    assert places(kb) == ["dock"]
    assert recover(kb) == []  # a recovery that ran is not done again
    assert places(kb) == ["dock"]
    assert len(logged(kb, "CANCEL", "move_to(dock, lab)")) == 1


def test_a_recovered_step_shows_as_cancelled_in_its_plan(
    executor: Executor, tmp_path: Path
) -> None:
    plan_id = executor.execute(move(0, "dock", "lab"), picture(1, "lab", ended(0)))
    executor.started("move_to(dock, lab)")
    assert [s.state for s in executor.kb.plan(plan_id).steps] == ["running", "pending"]

    kb = crashed(executor.kb, tmp_path)
    recover(kb)

    assert [s.state for s in kb.plan(plan_id).steps] == ["cancelled", "pending"]


class Starting(ScriptedRunner):
    """A runner whose steps never get past their configuration's start."""

    def run(self, step: Step, plan_id: int, report: StepReport) -> StepTask:
        task = ScriptedTask(step, report)
        self.tasks.append(task)
        return task


def test_a_step_dispatched_but_not_started_is_cancelled_without_taking_anything_back(
    usecase_kb: KnowledgeBase, tmp_path: Path
) -> None:
    usecase_kb.log_event("EXECUTIVE_STARTED", "usecase")
    executor = PlanExecutor(usecase_kb, Starting(), ("move_to",), lambda reason: None)
    executor.start()
    try:
        plan = PartialOrderPlan((move(0, "dock", "lab"),))
        plan_id = usecase_kb.store_plan(plan.records()).id
        executor.execute(plan, plan_id, [])
        eventually(lambda: bool(logged(usecase_kb, "DISPATCH", "move_to(dock, lab)")))
        kb = crashed(usecase_kb, tmp_path)
    finally:
        executor.stop()

    assert recover(kb) == ["move_to(dock, lab)"]
    (cancel,) = logged(kb, "CANCEL", "move_to(dock, lab)")
    (dispatch,) = logged(kb, "DISPATCH", "move_to(dock, lab)")
    assert cancel.data["run"] == dispatch.id and "undo" not in cancel.data
    assert places(kb) == ["dock"]
    assert kb.plan(plan_id).steps[0].state == "cancelled"


def test_a_log_written_before_runs_were_named_is_recovered_by_plan_and_step(
    usecase_kb: KnowledgeBase,
) -> None:
    kb = usecase_kb
    plan_id = kb.store_plan(
        PartialOrderPlan((move(0, "dock", "lab"), picture(1, "lab"))).records()
    ).id
    step = {"plan": plan_id, "action": "move_to", "args": ["dock", "lab"]}
    kb.log_event("DISPATCH", "move_to(dock, lab)", {**step, "step": 0})
    kb.log_event(
        "START", "move_to(dock, lab)", {**step, "step": 0, "undo": [["robot_at", ["dock"], True]]}
    )
    kb.log_event("DISPATCH", "take_picture(lab)", {**step, "step": 1})
    kb.log_event("END", "take_picture(lab)", {**step, "step": 1})
    kb.update_facts(remove=[Fact("robot_at", ("dock",))])

    assert recover(kb) == ["move_to(dock, lab)"]
    assert places(kb) == ["dock"]
    assert [s.state for s in kb.plan(plan_id).steps] == ["cancelled", "pending"]
