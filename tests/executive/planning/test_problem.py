"""Goals, worlds and the unified-planning problems built from them."""

from __future__ import annotations

import time
from pathlib import Path

import pytest

from executive.planning.goals import GoalSpec, Refusal, RefusalCause, remaining, specs, submit
from executive.planning.problem import build, frozen, read_world, seed_world
from knowledge.domain import parse
from knowledge.errors import DomainError
from knowledge.knowledge_base import KnowledgeBase
from knowledge.records import Fact, GoalState
from knowledge.robot import load_robot
from tests.conftest import USECASE
from tests.executive.planning.planning_cases import (
    USECASE_DOMAIN,
    USECASE_PROBLEM,
    expr,
    signature,
    usecase_domain,
    usecase_kb_fixture,  # noqa: F401 (a fixture)
    usecase_task,
    world,
)


def test_the_world_is_seeded_from_the_robots_problem_file_once(tmp_path: Path) -> None:
    robot = load_robot(USECASE)
    with KnowledgeBase(tmp_path / "kb.db") as kb:
        assert seed_world(kb, robot)
        assert kb.objects() == {"dock": "place", "lab": "place", "office": "place"}
        assert Fact("robot_at", ("dock",)) in kb.facts()
        assert Fact("travel_time", ("dock", "lab"), 4.0) in kb.facts()
        kb.update_facts(remove=[Fact("robot_at", ("dock",))], add=[Fact("robot_at", ("lab",))])
        assert not seed_world(kb, robot)  # the KB has a world: it is kept
        assert Fact("robot_at", ("lab",)) in kb.facts()


def test_a_valid_goal_is_stored_pending_and_an_invalid_one_is_refused_without_a_trace(
    usecase_kb: KnowledgeBase,
) -> None:
    domain = usecase_domain()
    goal = submit(usecase_kb, domain, "(and (picture_taken lab)\n (robot_at dock))", priority=3)
    assert goal.state is GoalState.PENDING
    assert goal.expression == "(and (picture_taken lab) (robot_at dock))"
    with pytest.raises(DomainError, match="unknown object 'lob'"):
        submit(usecase_kb, domain, "(picture_taken lob)")
    with pytest.raises(DomainError, match="deadline must be a positive"):
        submit(usecase_kb, domain, "(picture_taken lab)", deadline=0)
    with pytest.raises(DomainError, match="unknown source 'robot'"):
        submit(usecase_kb, domain, "(picture_taken lab)", source="robot")
    assert [g.id for g in usecase_kb.goals()] == [goal.id]


def test_goals_whose_deadline_passed_or_whose_objects_are_gone_are_not_planned(
    usecase_kb: KnowledgeBase,
) -> None:
    domain = usecase_domain()
    late = submit(usecase_kb, domain, "(picture_taken lab)", deadline=10)
    gone = submit(usecase_kb, domain, "(picture_taken office)")
    fine = submit(usecase_kb, domain, "(robot_at lab)", priority=2)
    usecase_kb.remove_object("office")
    now = time.time() + 11
    usable, refused = specs(usecase_kb.open_goals(), signature_of(usecase_kb), now)
    assert [(g.id, g.priority) for g in usable] == [(fine.id, 2)]
    assert refused[late.id] == Refusal(RefusalCause.DEADLINE_PASSED, "its deadline of 10 s passed")
    assert refused[gone.id].cause is RefusalCause.INVALID
    assert "unknown object 'office'" in refused[gone.id].reason
    assert remaining(late, late.created + 4) == pytest.approx(6)


def signature_of(kb: KnowledgeBase):  # type: ignore[no-untyped-def]
    from executive.planning.expression import Signature

    return Signature.of(usecase_domain(), kb.objects())


def test_a_problem_holds_the_world_the_goals_and_a_window_for_each_deadline() -> None:
    goals = [
        GoalSpec(1, expr("(picture_taken lab)")),
        GoalSpec(2, expr("(robot_at dock)"), 0, 12.5),
    ]
    problem = build(parse(USECASE_DOMAIN), world(USECASE_DOMAIN, USECASE_PROBLEM), goals)
    assert {o.name for o in problem.all_objects} == {"dock", "lab", "office"}
    assert len(problem.explicit_initial_values) >= 15
    assert [str(g) for g in problem.goals] == [
        "picture_taken(lab)",
        "robot_at(dock)",
        "dura_reached_2",
    ]
    ((timing, effects),) = problem.timed_effects.items()
    assert float(timing.delay) == 12.5
    assert [str(e) for e in effects] == ["dura_before_deadline_2 := false"]
    assert problem.action("dura_reach_goal_2") is not None


def test_blocked_actions_are_left_out_of_the_problem() -> None:
    domain = parse(USECASE_DOMAIN)
    problem = build(domain, world(USECASE_DOMAIN, USECASE_PROBLEM), [], {"take_picture"})
    assert [a.name for a in problem.actions] == [
        a.name for a in domain.actions if a.name != "take_picture"
    ]
    assert domain.has_action("take_picture")  # the domain itself is left as it was


def test_a_fact_the_domain_does_not_know_is_refused() -> None:
    bad = world(USECASE_DOMAIN, USECASE_PROBLEM)
    from executive.planning.problem import World

    with pytest.raises(DomainError, match=r"fact \(flying dock\): unknown predicate"):
        build(parse(USECASE_DOMAIN), World(bad.objects, (Fact("flying", ("dock",)),)), [])


def test_a_problem_file_that_does_not_fit_the_domain_names_file_and_line(tmp_path: Path) -> None:
    problem = tmp_path / "p.pddl"
    problem.write_text(
        "(define (problem p) (:domain usecase)\n (:objects a - place)\n (:init (robot_at b)))"
    )
    with pytest.raises(DomainError, match=rf"^{problem}:3:19: unknown object 'b'$"):
        read_world(USECASE_DOMAIN, problem)


def test_a_signature_knows_the_problem_objects() -> None:
    assert signature().objects_of("place") == ["dock", "lab", "office"]


def test_a_frozen_problem_computes_its_kind_once_and_its_clone_afresh() -> None:
    from unified_planning.model.metrics import MinimizeMakespan

    task = usecase_task("(picture_taken lab)")
    problem = build(parse(USECASE_DOMAIN), task.world, task.goals)
    assert problem.kind is not problem.kind  # unified-planning computes it at every look
    kept = frozen(problem)
    assert kept is problem and kept.kind is kept.kind
    assert kept.kind == build(parse(USECASE_DOMAIN), task.world, task.goals).kind
    clone = kept.clone()
    clone.add_quality_metric(MinimizeMakespan())
    assert clone.kind.has_quality_metrics() and not kept.kind.has_quality_metrics()
