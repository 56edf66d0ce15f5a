"""Integrity goals: YAML rules that post goals on faults, diagnoses and KB conditions."""

from __future__ import annotations

import subprocess
from collections.abc import Callable
from pathlib import Path

import pytest

from executive.planning.integrity import IntegrityGoals, read_rules
from executive.testing.harness import robot_variant
from knowledge.errors import ConfigError
from knowledge.knowledge_base import KnowledgeBase
from knowledge.records import Fact, GoalState
from knowledge.robot import load_robot
from tests.conftest import ROOT, USECASE
from tests.executive.planning.planning_cases import (
    TRANSPORT,
    usecase_domain,
    usecase_kb_fixture,  # noqa: F401 (a fixture)
)


def usecase_rules(
    kb: KnowledgeBase, text: str | None = None, tmp: Path | None = None
) -> IntegrityGoals:
    robot = load_robot(USECASE)
    path = ROOT / "examples" / "usecase" / "integrity.yaml"
    if text is not None and tmp is not None:
        path = tmp / "integrity.yaml"
        path.write_text(text)
    rules = read_rules(path, robot, usecase_domain(), kb.objects())
    return IntegrityGoals(kb, usecase_domain(), rules)


def test_lidar_becoming_permanently_faulty_posts_the_maintenance_goal_once(
    usecase_kb: KnowledgeBase,
) -> None:
    generator = usecase_rules(usecase_kb)
    usecase_kb.register_component("lidar", 10)
    assert generator.check() == []
    for _ in range(3):
        usecase_kb.record_fault("lidar", "no scans", max_faults=3)
    (goal,) = generator.check()
    assert (goal.expression, goal.priority, goal.source) == ("(robot_at dock)", 10, "integrity")
    assert goal.state is GoalState.PENDING
    assert generator.check() == []  # fires once while the fault lasts
    usecase_kb.reset_component("lidar")
    assert generator.check() == []
    usecase_kb.mark_permanent_fault("lidar", "broken again")
    usecase_kb.set_goal_state(goal.id, GoalState.ACHIEVED)
    assert [g.expression for g in generator.check()] == ["(robot_at dock)"]


def test_a_condition_over_numeric_facts_must_persist_before_its_goal_is_posted(
    usecase_kb: KnowledgeBase, tmp_path: Path
) -> None:
    rules = """
goals:
  - name: slow_path
    when: {condition: "(> (travel_time dock lab) 10)"}
    for: 5
    goal: "(picture_taken office)"
    priority: 3
    deadline: 60
"""
    generator = usecase_rules(usecase_kb, rules, tmp_path)
    assert generator.check(now=100) == []
    usecase_kb.set_fact(Fact("travel_time", ("dock", "lab"), 12.0))
    assert generator.check(now=101) == []
    assert generator.next_check() == 106
    (goal,) = generator.check(now=106)
    assert (goal.priority, goal.deadline) == (3, 60)
    assert [e.subject for e in usecase_kb.events(kind="INTEGRITY_GOAL")] == ["slow_path"]


def test_a_component_in_every_diagnosis_posts_a_goal(
    usecase_kb: KnowledgeBase, tmp_path: Path
) -> None:
    rules = "goals:\n  - {name: cam_check, when: {diagnosis: cam}, goal: '(robot_at dock)'}\n"
    generator = usecase_rules(usecase_kb, rules, tmp_path)
    usecase_kb.update_facts(remove=[Fact("robot_at", ("dock",))], add=[Fact("robot_at", ("lab",))])
    generator.diagnosed({"status": "ok", "diagnoses": [["cam"], ["cam_to_lidar"]], "stamp": 1.0})
    assert generator.check() == []  # cam might be fine
    generator.diagnosed({"status": "ok", "diagnoses": [["cam"], ["cam", "lidar"]], "stamp": 2.0})
    assert [g.expression for g in generator.check()] == ["(robot_at dock)"]


BAD_RULES = [
    (
        "goals:\n  - name: a\n    when: {permanent_fault: lidr}\n    goal: (robot_at dock)\n",
        ":3: integrity rule 'a' names unknown component 'lidr' (did you mean 'lidar'?)",
    ),
    (
        "goals:\n  - name: a\n    when: {permanent_fault: lidar}\n    goal: (robot_at dok)\n",
        ":4: integrity rule 'a': goal '(robot_at dok)': unknown object 'dok'",
    ),
    (
        "goals:\n  - name: a\n    when: {}\n    goal: (robot_at dock)\n",
        ":3: 'when' of integrity rule 'a' needs exactly one of permanent_fault, diagnosis, condition",
    ),
    (
        "goals:\n  - name: a\n    when: {condition: (robot_at dock)}\n    goal: (robot_at dock)\n    priorty: 3\n",
        ":5: unknown key 'priorty' in integrity rule 'a' (did you mean 'priority'?)",
    ),
]


@pytest.mark.parametrize(("text", "message"), BAD_RULES)
def test_rule_files_with_errors_name_the_file_and_line(
    usecase_kb: KnowledgeBase, tmp_path: Path, text: str, message: str
) -> None:
    with pytest.raises(ConfigError) as e:
        usecase_rules(usecase_kb, text, tmp_path)
    assert str(e.value) == f"{tmp_path / 'integrity.yaml'}{message}" or message in str(e.value)


def test_the_example_robots_integrity_rules_are_valid(tmp_path: Path) -> None:
    from executive.planning.problem import seed_world
    from knowledge.domain import read_domain

    for path in (USECASE, TRANSPORT):
        robot = load_robot(path)
        with KnowledgeBase(tmp_path / f"{robot.name}.db") as kb:
            seed_world(kb, robot)
            for file in robot.integrity:
                assert read_rules(file, robot, read_domain(robot.domain), kb.objects())


def test_dura_validate_checks_the_robots_integrity_and_repair_rules(
    tmp_path: Path, dura: Callable[..., subprocess.CompletedProcess[str]]
) -> None:
    robot = robot_variant(USECASE, tmp_path, {"rules": ["repair.yaml"]})
    (tmp_path / "integrity.yaml").unlink()  # a link to the example's file
    (tmp_path / "integrity.yaml").write_text(
        "goals:\n  - name: broken\n    when: {permanent_fault: lidar}\n"
        '    goal: "(robot_at nowhere)"\n'
    )
    (tmp_path / "repair.yaml").write_text("rules:\n  - name: r\n    action: {type: teleport}\n")
    done = dura("validate", str(robot))
    assert done.returncode == 1
    lines = done.stderr.splitlines()
    assert any(
        line.startswith(f"{tmp_path / 'integrity.yaml'}:4: ") and "nowhere" in line
        for line in lines
    ), lines
    assert any(line.startswith(f"{tmp_path / 'repair.yaml'}:") for line in lines), lines


def test_a_rule_with_keep_posts_a_maintenance_goal_that_is_not_posted_again_while_watched(
    usecase_kb: KnowledgeBase, tmp_path: Path
) -> None:
    rules = """
goals:
  - name: stay_home
    when: {permanent_fault: lidar}
    goal: (robot_at dock)
    keep: true
"""
    generator = usecase_rules(usecase_kb, rules, tmp_path)
    usecase_kb.register_component("lidar", 10)
    usecase_kb.mark_permanent_fault("lidar", "broken")
    (goal,) = generator.check()
    assert goal.keep
    usecase_kb.set_goal_state(goal.id, GoalState.ACHIEVED)  # watched from now on
    usecase_kb.reset_component("lidar")
    assert generator.check() == []
    usecase_kb.mark_permanent_fault("lidar", "broken again")
    assert generator.check() == []  # the same goal is achieved and watched: not posted twice
