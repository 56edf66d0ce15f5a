"""Errors of PDDL files in dura's words: ``file:line:col: reason`` at the place to fix,
with a did-you-mean, the domain's own parameter names, and the source line with a caret
under the place for a terminal. Each case breaks the warehouse domain (a type hierarchy
three levels deep) or its problem as users do."""

from __future__ import annotations

from pathlib import Path

import pytest

from knowledge.domain import parse_problem, read_domain
from knowledge.errors import DomainError
from tests.conftest import run_dura
from tests.executive.planning.planning_cases import (
    WAREHOUSE_DOMAIN,
    WAREHOUSE_PROBLEM,
    warehouse_robot,
)

# (what is broken, the text replaced, its replacement, the expected one line)
DOMAIN_CASES = [
    (
        "a misspelt predicate",
        "(at start (free ?v))",
        "(at start (fre ?v))",
        "23:76: unknown predicate 'fre' (did you mean 'free'?)",
    ),
    (
        "a wrong arity",
        "(at end (holding ?v ?c))",
        "(at end (holding ?c))",
        "25:26: 'holding' takes 2 arguments (?v - robot ?c - crate), not 1",
    ),
    (
        "an unknown type of a parameter",
        ":parameters (?v - robot ?p - dock)",
        ":parameters (?v - robot ?p - dok)",
        "32:34: unknown type 'dok' (did you mean 'dock'?)",
    ),
    (
        "an unknown type of a predicate",
        "(holding ?v - robot ?c - crate)",
        "(holding ?v - robot ?c - crat)",
        "12:30: unknown type 'crat' (did you mean 'crate'?)",
    ),
    (
        "an unknown parameter",
        "(at end (at ?v ?to))",
        "(at end (at ?v ?too))",
        "19:64: unknown parameter '?too' (did you mean '?to'?)",
    ),
    (
        "a missing ')' in a condition",
        "(over all (road ?from ?to)))",
        "(over all (road ?from ?to))",
        "18:16: '(and' is not closed before ':effect' at line 19 (a ')' is missing)",
    ),
    (
        "a missing ')' in the predicates",
        "(free ?v - robot)",
        "(free ?v - robot",
        "13:5: '(free' is not closed before '(battery_low' at line 14 (a ')' is missing)",
    ),
    (
        "a ')' too many",
        "(over all (road ?from ?to)))",
        "(over all (road ?from ?to))))",
        "19:5: ':effect' is outside any action: a ')' before it closes the action too early",
    ),
    (
        "a misspelt keyword",
        ":condition (over all (at ?v ?p))",
        ":condtion (over all (at ?v ?p))",
        "34:5: unknown keyword ':condtion' (did you mean ':condition'?)",
    ),
    (
        "an either type",
        "(at ?x - locatable ?p - place)",
        "(at ?x - (either vehicle crate) ?p - place)",
        "10:14: unified-planning's reader does not read 'either' types: declare a common "
        "supertype and use it instead",
    ),
    (
        "a misspelt section",
        "(:predicates",
        "(:predicats",
        "9:3: unknown section '(:predicats' (did you mean ':predicates'?)",
    ),
    (
        "?duration in a condition",
        "(over all (road ?from ?to))",
        "(over all (road ?from ?duration))",
        "18:68: unified-planning's reader does not read '?duration' outside the :duration "
        "constraint",
    ),
]

PROBLEM_CASES = [
    (
        "a misspelt predicate",
        "(free robot)",
        "(fre robot)",
        "8:22: unknown predicate 'fre' (did you mean 'free'?)",
    ),
    (
        "an unknown object",
        "(at parcel store)",
        "(at parcel stor)",
        "8:45: unknown object 'stor' (did you mean 'store'?)",
    ),
    (
        "an unknown type",
        "parcel - crate)",
        "parcel - crat)",
        "6:14: unknown type 'crat' (did you mean 'crate'?)",
    ),
    (
        "a wrong arity",
        "(free robot)",
        "(free robot dock)",
        "8:21: 'free' takes 1 argument (?v - robot), not 2",
    ),
    (
        "a missing ')'",
        "(free robot)",
        "(free robot",
        "8:21: '(free' is not closed before '(at' at line 8 (a ')' is missing)",
    ),
    (
        "an object of type object",
        "parcel - crate)",
        "parcel - crate thing - object)",
        "6:28: unified-planning's reader does not read objects declared '- object': give them "
        "a type of the domain",
    ),
    (
        "another domain",
        "(:domain warehouse)",
        "(:domain warehose)",
        "1:24: the problem is for domain 'warehose', not 'warehouse'",
    ),
]


def broken(text: str, old: str, new: str) -> str:
    assert text.count(old) == 1, old
    return text.replace(old, new)


@pytest.mark.parametrize(("what", "old", "new", "expected"), DOMAIN_CASES)
def test_a_broken_domain_is_one_line_at_the_place_to_fix(
    tmp_path: Path, what: str, old: str, new: str, expected: str
) -> None:
    path = tmp_path / "domain.pddl"
    path.write_text(broken(WAREHOUSE_DOMAIN, old, new))
    with pytest.raises(DomainError) as error:
        read_domain(path)
    assert str(error.value) == f"{path}:{expected}"
    line, column = (int(n) for n in expected.split(":")[:2])
    source, caret = error.value.excerpt.splitlines()
    assert source.endswith(path.read_text().splitlines()[line - 1].rstrip())
    assert caret.index("^") - caret.index("|") == column + 1  # "| ", then column - 1 places


@pytest.mark.parametrize(("what", "old", "new", "expected"), PROBLEM_CASES)
def test_a_broken_problem_is_one_line_at_the_place_to_fix(
    tmp_path: Path, what: str, old: str, new: str, expected: str
) -> None:
    domain = tmp_path / "domain.pddl"
    domain.write_text(WAREHOUSE_DOMAIN)
    with pytest.raises(DomainError) as error:
        parse_problem(domain, broken(WAREHOUSE_PROBLEM, old, new), "problem.pddl")
    assert str(error.value) == f"problem.pddl:{expected}"


def test_a_problem_given_for_the_domain_and_a_domain_for_the_problem_are_named(
    tmp_path: Path,
) -> None:
    domain, problem = tmp_path / "domain.pddl", tmp_path / "problem.pddl"
    domain.write_text(WAREHOUSE_DOMAIN)
    problem.write_text(WAREHOUSE_PROBLEM)
    with pytest.raises(DomainError) as swapped:
        read_domain(problem)
    assert str(swapped.value) == f"{problem}:1:10: this file is a PDDL problem, not a domain"
    with pytest.raises(DomainError) as twice:
        parse_problem(domain, WAREHOUSE_DOMAIN, "domain.pddl")
    assert str(twice.value) == "domain.pddl:2:10: this file is a PDDL domain, not a problem"


def test_the_caret_stands_under_the_place_also_after_tabs(tmp_path: Path) -> None:
    path = tmp_path / "domain.pddl"
    path.write_text(broken(WAREHOUSE_DOMAIN, "    (free ?v - robot)", "\t(free ?v - robbot)"))
    with pytest.raises(DomainError) as error:
        read_domain(path)
    assert str(error.value) == f"{path}:13:13: unknown type 'robbot' (did you mean 'robot'?)"
    assert error.value.excerpt == "   13 | \t(free ?v - robbot)\n      | \t" + " " * 11 + "^"


def test_dura_validate_prints_the_line_then_the_source_and_stores_nothing(
    tmp_path: Path,
) -> None:
    robot = warehouse_robot(tmp_path / "warehouse")
    domain = robot.parent / "domain.pddl"
    domain.write_text(broken(WAREHOUSE_DOMAIN, "(at start (free ?v))", "(at start (fre ?v))"))
    done = run_dura("validate", "robot.yaml", cwd=robot.parent)
    assert done.returncode == 1
    assert done.stdout == ""
    assert done.stderr.splitlines() == [
        "domain.pddl:23:76: unknown predicate 'fre' (did you mean 'free'?)",
        "   23 |     :condition (and (over all (at ?v ?p)) (at start (at ?c ?p)) (at start (fre ?v)))",
        "      | " + " " * 75 + "^",
    ]
    assert not (robot.parent / ".dura").exists()  # nothing stored
    json = run_dura("validate", "robot.yaml", "--json", cwd=robot.parent)
    assert json.returncode == 1
    assert '"column": 76' in json.stdout
    assert "^" not in json.stdout + json.stderr


def test_dura_domain_check_and_plan_offline_say_the_same_one_line(tmp_path: Path) -> None:
    robot = warehouse_robot(tmp_path / "warehouse")
    domain = robot.parent / "domain.pddl"
    domain.write_text(broken(WAREHOUSE_DOMAIN, "(at end (holding ?v ?c))", "(at end (holding ?c))"))
    line = "dura: domain.pddl:25:26: 'holding' takes 2 arguments (?v - robot ?c - crate), not 1"
    check = run_dura("domain", "check", "domain.pddl", cwd=robot.parent)
    assert check.returncode == 1
    assert check.stderr.splitlines()[0] == line
    plan = run_dura("plan", "--offline", "domain.pddl", "problem.pddl", cwd=robot.parent)
    assert plan.returncode == 1
    assert plan.stderr.splitlines()[0] == line
    assert "kairos" not in plan.stderr  # no engine ran


def test_a_problem_for_another_domain_is_refused_before_any_engine_runs(tmp_path: Path) -> None:
    robot = warehouse_robot(tmp_path / "warehouse")
    problem = robot.parent / "problem.pddl"
    problem.write_text(broken(WAREHOUSE_PROBLEM, "(:domain warehouse)", "(:domain depots)"))
    done = run_dura("plan", "--offline", "domain.pddl", "problem.pddl", cwd=robot.parent)
    assert done.returncode == 1
    assert done.stdout == ""
    assert done.stderr.splitlines()[0] == (
        "dura: problem.pddl:1:24: the problem is for domain 'depots', not 'warehouse'"
    )
