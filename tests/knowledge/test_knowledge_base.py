"""The knowledge base: typed records, one transaction per change, crash safety."""

from __future__ import annotations

import signal
import sqlite3
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest

from knowledge.errors import KnowledgeError
from knowledge.knowledge_base import KnowledgeBase
from knowledge.records import (
    GOAL_TRANSITIONS,
    Fact,
    GoalState,
    PlanState,
    PlanStep,
    TaskState,
)
from knowledge.schema import VERSION
from tests.conftest import ROOT


@pytest.fixture
def kb(tmp_path: Path) -> KnowledgeBase:
    with KnowledgeBase(tmp_path / "robot.db") as base:
        yield base  # type: ignore[misc]


def test_a_new_knowledge_base_uses_wal_and_the_current_schema(tmp_path: Path) -> None:
    with KnowledgeBase(tmp_path / "sub" / "r.db") as kb:
        assert kb.schema_version == VERSION
    db = sqlite3.connect(tmp_path / "sub" / "r.db")
    assert db.execute("PRAGMA journal_mode").fetchone()[0] == "wal"
    db.close()


def test_a_database_from_a_newer_dura_is_refused(tmp_path: Path) -> None:
    db = sqlite3.connect(tmp_path / "r.db")
    db.execute(f"PRAGMA user_version={VERSION + 1}")
    db.close()
    with pytest.raises(KnowledgeError, match="newer than this dura"):
        KnowledgeBase(tmp_path / "r.db")


def test_a_goal_goes_through_its_lifecycle_and_leaves_events(kb: KnowledgeBase) -> None:
    goal = kb.add_goal("(picture_taken lab)", priority=3, deadline=60.0)
    assert goal.state is GoalState.PENDING and goal.priority == 3 and goal.deadline == 60.0
    assert kb.open_goals() == [goal]
    kb.set_goal_state(goal.id, GoalState.PLANNED)
    done = kb.set_goal_state(goal.id, GoalState.ACHIEVED)
    assert done.state is GoalState.ACHIEVED
    assert kb.open_goals() == []
    assert [e.kind for e in kb.events()] == ["GOAL_ADDED", "GOAL_PLANNED", "GOAL_ACHIEVED"]


def test_an_unknown_goal_is_an_error_and_changes_nothing(kb: KnowledgeBase) -> None:
    with pytest.raises(KnowledgeError, match="no goal 42"):
        kb.set_goal_state(42, GoalState.CANCELLED)
    assert kb.events() == []


def test_a_cancelled_goal_cannot_be_planned_again(kb: KnowledgeBase) -> None:
    goal = kb.add_goal("(picture_taken lab)")
    kb.set_goal_state(goal.id, GoalState.CANCELLED)
    with pytest.raises(KnowledgeError, match=r"^goal 1: cannot go from cancelled to planned$"):
        kb.set_goal_state(goal.id, GoalState.PLANNED)
    assert kb.goal(goal.id).state is GoalState.CANCELLED
    assert [e.kind for e in kb.events()] == ["GOAL_ADDED", "GOAL_CANCELLED"]


@pytest.mark.parametrize("end", [s for s in GoalState if s.is_final])
def test_a_goal_that_ended_stays_as_it_ended(kb: KnowledgeBase, end: GoalState) -> None:
    goal = kb.add_goal("(a)")
    kb.set_goal_state(goal.id, end)
    for state in GoalState:
        with pytest.raises(KnowledgeError, match=f"cannot go from {end.value} to {state.value}"):
            kb.set_goal_state(goal.id, state)
    assert GOAL_TRANSITIONS[end] == frozenset()
    assert [s for s in GoalState if s.is_final] == [
        GoalState.ACHIEVED, GoalState.FAILED, GoalState.CANCELLED
    ]  # fmt: skip


def test_an_unreachable_goal_may_be_reposted_get_a_new_reason_or_be_cancelled(
    kb: KnowledgeBase,
) -> None:
    goal = kb.add_goal("(a)")
    kb.set_goal_state(goal.id, GoalState.UNREACHABLE, "no plan")
    assert kb.set_goal_state(goal.id, GoalState.UNREACHABLE, "still none").reason == "still none"
    with pytest.raises(KnowledgeError, match="cannot go from unreachable to achieved"):
        kb.set_goal_state(goal.id, GoalState.ACHIEVED)
    assert kb.set_goal_state(goal.id, GoalState.PENDING, "reachable again").state.is_open
    kb.set_goal_state(goal.id, GoalState.UNREACHABLE, "no plan")
    assert kb.set_goal_state(goal.id, GoalState.CANCELLED).state is GoalState.CANCELLED


def test_an_achieved_maintenance_goal_may_be_reposted_and_a_plain_one_not(
    kb: KnowledgeBase,
) -> None:
    kept = kb.add_goal("(a)", keep=True)
    once = kb.add_goal("(a)")
    assert kept.keep and not once.keep
    for goal in (kept, once):
        kb.set_goal_state(goal.id, GoalState.ACHIEVED)
    assert kb.set_goal_state(kept.id, GoalState.PENDING, "stopped holding").state.is_open
    with pytest.raises(KnowledgeError, match="goal 2: cannot go from achieved to pending"):
        kb.set_goal_state(once.id, GoalState.PENDING)
    assert kb.events(kind="GOAL_ADDED")[0].data == {"expression": "(a)", "keep": True}


def test_an_open_goal_is_planned_before_it_executes_and_may_be_planned_again(
    kb: KnowledgeBase,
) -> None:
    goal = kb.add_goal("(a)")
    with pytest.raises(KnowledgeError, match="goal 1: cannot go from pending to executing"):
        kb.set_goal_state(goal.id, GoalState.EXECUTING)
    for state in (GoalState.PLANNED, GoalState.EXECUTING, GoalState.PLANNED, GoalState.PLANNED):
        assert kb.set_goal_state(goal.id, state).state is state
    assert kb.set_goal_state(goal.id, GoalState.UNREACHABLE, "no plan").reason == "no plan"


def test_a_superseded_plan_cannot_fail_or_succeed_afterwards(kb: KnowledgeBase) -> None:
    first = kb.store_plan([PlanStep(0, "move_to", ("dock", "lab"), 0.0, 4.0)])
    kb.set_plan_state(first.id, PlanState.EXECUTING)
    kb.store_plan([])
    for state in (PlanState.FAILED, PlanState.SUCCEEDED, PlanState.EXECUTING):
        with pytest.raises(
            KnowledgeError, match=f"^plan 1: cannot go from superseded to {state.value}$"
        ):
            kb.set_plan_state(first.id, state, "too late")
    assert kb.plan(first.id).state is PlanState.SUPERSEDED and kb.plan(first.id).reason == ""
    with pytest.raises(KnowledgeError, match="no plan 9"):
        kb.set_plan_state(9, PlanState.FAILED)


def test_a_refused_transition_rolls_back_its_whole_transaction(kb: KnowledgeBase) -> None:
    goal = kb.add_goal("(a)")
    kb.set_goal_state(goal.id, GoalState.ACHIEVED)
    with pytest.raises(KnowledgeError, match="cannot go from achieved to failed"), kb.transaction():
        kb.set_fact(Fact("b"))
        kb.set_goal_state(goal.id, GoalState.FAILED, "too late")
    assert kb.facts() == [] and kb.goal(goal.id).state is GoalState.ACHIEVED


def test_a_failed_transaction_leaves_nothing_behind(kb: KnowledgeBase) -> None:
    with pytest.raises(KnowledgeError), kb.transaction():
        kb.add_goal("(a)")
        kb.set_fact(Fact("b"))
        kb.set_goal_state(999, GoalState.FAILED)
    assert kb.goals() == [] and kb.facts() == [] and kb.events() == []


def test_listeners_hear_committed_events_only_once_their_transaction_commits(
    kb: KnowledgeBase,
) -> None:
    heard: list[str] = []
    kb.add_listener(lambda e: heard.append(f"{e.kind} {e.subject}"))
    with kb.transaction():
        kb.add_goal("(a)")
        assert heard == []  # not yet committed
    with pytest.raises(KnowledgeError), kb.transaction():
        kb.log_event("LOST")
        kb.set_goal_state(999, GoalState.FAILED)
    kb.log_event("KEPT", "x", {"n": 1})
    assert heard == ["GOAL_ADDED goal 1", "KEPT x"]
    assert [e.id for e in kb.events()] == [1, 2]


def test_a_failing_listener_does_not_stop_the_others(kb: KnowledgeBase) -> None:
    heard: list[str] = []

    def broken(_: object) -> None:
        raise RuntimeError("listener bug")

    kb.add_listener(broken)
    kb.add_listener(lambda e: heard.append(e.kind))
    kb.log_event("ONE")
    assert heard == ["ONE"]


def test_a_new_plan_supersedes_the_open_one(kb: KnowledgeBase) -> None:
    first = kb.store_plan([PlanStep(0, "move_to", ("dock", "lab"), 0.0, 4.0)], engine="kairos")
    kb.set_plan_state(first.id, PlanState.EXECUTING)
    second = kb.store_plan(
        [
            PlanStep(0, "take_picture", ("lab",), 0.0, 2.0),
            PlanStep(1, "move_to", ("lab", "dock"), 2.0, 4.0),
        ],
        goal_ids=[7],
    )
    assert kb.plan(first.id).state is PlanState.SUPERSEDED
    assert kb.latest_plan() == second
    assert second.steps[1].args == ("lab", "dock") and second.goal_ids == (7,)


def test_a_plan_step_keeps_what_happened_to_it_and_refuses_an_unknown_state(
    kb: KnowledgeBase,
) -> None:
    plan = kb.store_plan([PlanStep(0, "move_to", ("dock", "lab"), 0.0, 4.0)])
    assert plan.steps[0].state == "pending"
    kb.set_step_state(plan.id, 0, "running")
    kb.set_step_state(plan.id, 0, "cancelled")
    assert kb.plan(plan.id).steps[0].state == "cancelled"
    with pytest.raises(KnowledgeError, match="unknown step state 'lost'"):
        kb.set_step_state(plan.id, 0, "lost")
    with pytest.raises(KnowledgeError, match="plan 1 has no step 3"):
        kb.set_step_state(plan.id, 3, "ended")


def test_a_plan_whose_goals_are_gone_is_cancelled_for_good(kb: KnowledgeBase) -> None:
    plan = kb.store_plan([])
    kb.set_plan_state(plan.id, PlanState.EXECUTING)
    assert kb.set_plan_state(plan.id, PlanState.CANCELLED, "goal 1 cancelled").reason
    with pytest.raises(KnowledgeError, match="cannot go from cancelled to executing"):
        kb.set_plan_state(plan.id, PlanState.EXECUTING)
    kb.store_plan([])
    assert kb.plan(plan.id).state is PlanState.CANCELLED  # not superseded afterwards


def test_events_are_read_by_one_kind_or_several(kb: KnowledgeBase) -> None:
    for kind in ("START", "TICK", "END", "TICK", "CANCEL"):
        kb.log_event(kind)
    assert [e.kind for e in kb.events(kinds=("START", "END", "CANCEL"))] == [
        "START",
        "END",
        "CANCEL",
    ]
    assert [e.id for e in kb.events(kind="TICK", after=2)] == [4]


def test_tasks_keep_their_arguments_state_and_result(kb: KnowledgeBase) -> None:
    task = kb.add_task("move_to", "move_to", {"start": "dock", "target": "lab"})
    kb.set_task_state(task.id, TaskState.RUNNING)
    kb.set_task_state(task.id, TaskState.SUCCEEDED, result={"distance": 4.2})
    stored = kb.task(task.id)
    assert stored.args == {"start": "dock", "target": "lab"}
    assert stored.state is TaskState.SUCCEEDED and stored.result == {"distance": 4.2}
    assert kb.tasks([TaskState.RUNNING]) == []


def test_facts_hold_atoms_and_numbers_and_effects_apply_deletes_first(kb: KnowledgeBase) -> None:
    kb.add_object("dock", "place")
    kb.update_facts(add=[Fact("robot_at", ("dock",)), Fact("travel_time", ("dock", "lab"), 4.0)])
    kb.update_facts(remove=[Fact("robot_at", ("dock",))], add=[Fact("robot_at", ("dock",))])
    assert [str(f) for f in kb.facts()] == ["(robot_at dock)", "(= (travel_time dock lab) 4)"]
    kb.unset_fact(Fact("robot_at", ("dock",)))
    assert kb.facts("robot_at") == []
    assert kb.objects() == {"dock": "place"}


def test_a_component_becomes_permanently_faulty_at_max_faults_and_can_be_reset(
    kb: KnowledgeBase,
) -> None:
    kb.register_component("lidar", 10)
    counts = [kb.record_fault("lidar", "crashed", max_faults=3) for _ in range(3)]
    assert [(c.fault_count, c.permanent_fault) for c in counts] == [
        (1, False),
        (2, False),
        (3, True),
    ]
    assert kb.register_component("lidar", 99).fault_count == 3  # history survives re-registration
    assert [e.kind for e in kb.events(kind="PERMANENT_FAULT")] == ["PERMANENT_FAULT"]
    reset = kb.reset_component("lidar")
    assert (reset.fault_count, reset.permanent_fault) == (0, False)


def test_achievements_parameters_and_return_values_round_trip(kb: KnowledgeBase) -> None:
    kb.set_achievement("move_to", "waypoint", 3)
    kb.set_parameter("lidar", "rate", 5.0)
    task = kb.add_task("take_picture", "take_picture")
    kb.store_return_value("take_picture", {"file": "lab.png"}, task_id=task.id)
    assert kb.achievements("move_to") == {"waypoint": 3}
    assert kb.parameters("lidar") == {"rate": 5.0}
    assert kb.return_values(task_id=task.id) == [{"file": "lab.png"}]
    kb.clear_achievements("move_to")
    assert kb.achievements("move_to") == {}


def test_a_reader_is_not_blocked_by_an_open_write_transaction(tmp_path: Path) -> None:
    writer = KnowledgeBase(tmp_path / "r.db")
    writer.add_goal("(first)")
    reader = KnowledgeBase(tmp_path / "r.db", readonly=True)
    inside = threading.Event()
    release = threading.Event()

    def hold() -> None:
        with writer.transaction():
            writer.add_goal("(second)")
            inside.set()
            release.wait(5)

    holder = threading.Thread(target=hold)
    holder.start()
    inside.wait(5)
    started = time.monotonic()
    assert [g.expression for g in reader.goals()] == ["(first)"]
    assert time.monotonic() - started < 1.0
    release.set()
    holder.join()
    assert [g.expression for g in reader.goals()] == ["(first)", "(second)"]
    with pytest.raises(KnowledgeError, match="read-only"):
        reader.add_goal("(third)")
    reader.close()
    writer.close()


def test_a_read_only_open_of_a_missing_file_is_an_error(tmp_path: Path) -> None:
    with pytest.raises(KnowledgeError, match="no knowledge base here"):
        KnowledgeBase(tmp_path / "none.db", readonly=True)


def test_every_committed_change_survives_a_sigkill_of_the_writer(tmp_path: Path) -> None:
    path = tmp_path / "crash.db"
    writer = subprocess.Popen(
        [sys.executable, "-m", "tests.knowledge.kb_writer", str(path)],
        stdout=subprocess.PIPE,
        text=True,
        cwd=ROOT,
    )
    assert writer.stdout is not None
    committed: list[int] = []
    for line in writer.stdout:
        committed.append(int(line))
        if len(committed) >= 300:
            break
    writer.send_signal(signal.SIGKILL)
    writer.wait(10)
    writer.stdout.close()
    assert writer.returncode == -signal.SIGKILL
    with KnowledgeBase(path) as kb:
        assert kb.integrity_check() == "ok"
        goal_ids = {g.id for g in kb.goals()}
        assert set(committed) <= goal_ids
        n = len(goal_ids)
        # each iteration was all-or-nothing: goal, fact, fault and event together
        assert len(kb.facts("visited")) == n
        assert kb.component("lidar").fault_count == n
        assert len(kb.events(kind="TICK")) == n


def test_the_event_log_is_in_the_order_of_its_stamps_whoever_writes(kb: KnowledgeBase) -> None:
    def write(name: str) -> None:
        for i in range(200):
            kb.log_event("TICK", name, {"i": i})

    writers = [threading.Thread(target=write, args=(f"w{n}",)) for n in range(4)]
    for writer in writers:
        writer.start()
    for writer in writers:
        writer.join()
    stamps = [e.stamp for e in kb.events(kind="TICK")]
    assert len(stamps) == 800 and stamps == sorted(stamps)


def test_the_kept_goals_are_the_achieved_maintenance_goals_read_by_an_index(
    kb: KnowledgeBase,
) -> None:
    """Asked on every change of facts: it must not read every goal the robot ever achieved
    (in a long run that cost memory and time per goal)."""
    kept, once, open_kept = (kb.add_goal(e, keep=k) for e, k in
                             (("(a)", True), ("(b)", False), ("(c)", True)))  # fmt: skip
    for goal in (kept, once):
        kb.set_goal_state(goal.id, GoalState.ACHIEVED)
    assert [g.id for g in kb.kept_goals()] == [kept.id]
    assert open_kept.id not in {g.id for g in kb.kept_goals()}
    for sql, params, index in (
        ("SELECT * FROM goals WHERE keep = 1 AND state = ? ORDER BY id", ("achieved",), "goals_kept"),
        ("SELECT min(id) FROM events WHERE subject = ?", ("goal 1",), "events_subject"),
    ):  # fmt: skip
        plan = " ".join(str(r[-1]) for r in kb._query(f"EXPLAIN QUERY PLAN {sql}", params))
        assert f"USING COVERING INDEX {index}" in plan or f"USING INDEX {index}" in plan, plan


def test_the_first_event_of_a_subject(kb: KnowledgeBase) -> None:
    assert kb.first_event("goal 1") is None
    goal = kb.add_goal("(a)")
    kb.log_event("NOTE", "goal 2")
    kb.set_goal_state(goal.id, GoalState.CANCELLED)
    first = kb.first_event(f"goal {goal.id}")
    assert first is not None
    assert kb.events(kind="GOAL_ADDED")[0].id == first


def test_goals_are_read_a_page_at_a_time_newest_first_in_sql(kb: KnowledgeBase) -> None:
    """A long run's goals are many: a page is the newest ``limit`` goals before one,
    given oldest first."""
    for n in range(10):
        goal = kb.add_goal(f"(g{n})")
        if n % 2:
            kb.set_goal_state(goal.id, GoalState.CANCELLED)
    assert [g.id for g in kb.goals(limit=3)] == [8, 9, 10]
    assert [g.id for g in kb.goals(before=8, limit=3)] == [5, 6, 7]
    assert [g.id for g in kb.goals(before=3, limit=3)] == [1, 2]
    assert [g.id for g in kb.goals(before=4)] == [1, 2, 3]
    assert [g.id for g in kb.goals([GoalState.CANCELLED], before=8, limit=2)] == [4, 6]
    assert kb.goals(limit=0) == []
    assert [g.id for g in kb.goals()] == list(range(1, 11))
    assert kb.goal_counts() == {GoalState.PENDING: 5, GoalState.CANCELLED: 5}
