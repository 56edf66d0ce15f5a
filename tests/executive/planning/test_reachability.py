"""Relaxed reachability and `dura domain check`: what can never hold, and why."""

from __future__ import annotations

from pathlib import Path

from executive.planning.domain_check import check_domain
from executive.planning.planner import Planner
from executive.planning.reachability import closure, ground, missing_atoms, problem_facts
from knowledge.domain import parse_problem
from tests.conftest import run_dura
from tests.executive.planning.planning_cases import (
    FLAWED_DOMAIN,
    FLAWED_PROBLEM,
    TRANSPORT_DOMAIN,
    TRANSPORT_PROBLEM,
    USECASE_DOMAIN,
    USECASE_PROBLEM,
    expr,
    kairos_fixture,  # noqa: F401 (a fixture)
    usecase_task,
)


def flawed(tmp_path: Path) -> tuple[Path, Path]:
    domain, problem = tmp_path / "domain.pddl", tmp_path / "problem.pddl"
    domain.write_text(FLAWED_DOMAIN)
    problem.write_text(FLAWED_PROBLEM)
    return domain, problem


def test_a_goal_atom_no_action_can_make_true_is_named_with_what_its_actions_need() -> None:
    problem = parse_problem(USECASE_DOMAIN, USECASE_PROBLEM.read_text(), "usecase")
    goal = expr("(and (picture_taken dock) (picture_taken lab))")
    assert missing_atoms(problem, [goal]) == (
        "(picture_taken dock) cannot become true: take_picture(dock) needs (photographable dock)",
    )


def test_the_relaxation_reaches_everything_the_transport_robot_can_do() -> None:
    problem = parse_problem(TRANSPORT_DOMAIN, TRANSPORT_PROBLEM.read_text(), "transport")
    actions = ground(problem)
    assert actions is not None
    reach = closure(actions, problem_facts(problem))
    applied = {actions[i].name for i in reach.applied}
    assert applied == {a.name for a in problem.actions}
    assert reach.holds(expr("(crate_at parcel lab)", TRANSPORT_DOMAIN, TRANSPORT_PROBLEM))


def test_the_planner_says_what_an_unreachable_goal_misses(kairos: Planner) -> None:
    result = kairos.solve(usecase_task("(picture_taken dock)"))
    assert not result.ok
    assert result.missing == (
        "(picture_taken dock) cannot become true: take_picture(dock) needs (photographable dock)",
    )


def test_domain_check_names_every_flaw_at_its_line(tmp_path: Path) -> None:
    domain, problem = flawed(tmp_path)
    found = [(Path(f.path).name, f.line, f.message) for f in check_domain(domain, problem)]
    assert found == [
        ("domain.pddl", 3, "type 'gadget' is not used"),
        (
            "domain.pddl",
            7,
            "predicate 'charged' is needed by drive and deleted by drive, but no action adds "
            "it: once used up it never holds again",
        ),
        (
            "domain.pddl",
            8,
            "predicate 'door_open' is needed by enter, but no action adds it and the initial "
            "state of problem.pddl has none: it never holds",
        ),
        ("domain.pddl", 9, "predicate 'painted' is not used by any action or the problem"),
        (
            "domain.pddl",
            16,
            "action 'enter' can never be applied from the initial state of problem.pddl: "
            "e.g. enter(r1, a) needs (door_open a)",
        ),
        (
            "problem.pddl",
            4,
            "goal: (at r1 c) cannot become true: drive(r1, a, c) needs (road a c); "
            "drive(r1, b, c) needs (road b c) (and 1 more)",
        ),
        (
            "problem.pddl",
            4,
            "goal: (visited b) cannot become true: enter(r1, b) needs (door_open b)",
        ),
    ]


def test_dura_domain_check_prints_file_line_warnings_and_exits_0(tmp_path: Path) -> None:
    domain, problem = flawed(tmp_path)
    done = run_dura("domain", "check", str(domain), str(problem), cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    lines = done.stdout.splitlines()
    assert lines[0] == "domain.pddl:3: warning: type 'gadget' is not used"
    assert len(lines) == 7
    assert done.stderr.strip() == "domain.pddl with problem.pddl: 7 warnings"


def test_dura_domain_check_finds_nothing_in_the_example_domains() -> None:
    for domain, problem in (
        (USECASE_DOMAIN, USECASE_PROBLEM),
        (TRANSPORT_DOMAIN, TRANSPORT_PROBLEM),
    ):
        assert check_domain(domain, problem) == []
        assert check_domain(domain) == []


def test_invalid_pddl_is_an_error_with_its_line(tmp_path: Path) -> None:
    (tmp_path / "broken.pddl").write_text("(define (domain broken)\n  (:predicates (a)\n")
    done = run_dura("domain", "check", "broken.pddl", cwd=tmp_path)
    assert done.returncode == 1
    assert done.stderr.splitlines() == [
        "dura: broken.pddl:2:3: '(:predicates' is not closed before the end of the file "
        "(a ')' is missing)",
        "    2 |   (:predicates (a)",
        "      |   ^",
    ], done.stderr
