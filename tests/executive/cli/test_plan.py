"""``dura plan --offline``: planning for domain authors, as a user runs it."""

from __future__ import annotations

import json
import subprocess
from collections.abc import Callable
from pathlib import Path

from tests.executive.planning.planning_cases import (
    TRANSPORT_DOMAIN,
    TRANSPORT_PROBLEM,
    USECASE_DOMAIN,
)
from tests.executive.planning.planning_cases import USECASE_PROBLEM as ROOT_PROBLEM

Dura = Callable[..., subprocess.CompletedProcess[str]]


def with_goal(tmp_path: Path, problem: Path, goal: str) -> Path:
    out = tmp_path / problem.name
    out.write_text(problem.read_text().replace("(:goal (and))", f"(:goal {goal})"))
    return out


def test_dura_plan_offline_prints_a_validated_plan_as_a_timeline(
    dura: Dura, tmp_path: Path
) -> None:
    problem = with_goal(tmp_path, TRANSPORT_PROBLEM, "(and (crate_at parcel lab) (robot_at dock))")
    done = dura("plan", "--offline", str(TRANSPORT_DOMAIN), str(problem))
    assert done.returncode == 0, done.stderr
    lines = done.stdout.splitlines()
    assert "steps, makespan" in lines[0] and "validated by" in lines[0]
    assert lines[1].split()[:5] == ["#", "START", "DURATION", "STEP", "AFTER"]
    assert any("pick(parcel, store)" in line and "█" in line for line in lines)


def test_dura_plan_offline_json_gives_steps_with_their_precedences(
    dura: Dura, tmp_path: Path
) -> None:
    problem = with_goal(tmp_path, TRANSPORT_PROBLEM, "(robot_at lab)")
    done = dura(
        "plan", "--offline", str(TRANSPORT_DOMAIN), str(problem), "--json", "--engine", "aries"
    )
    assert done.returncode == 0, done.stderr
    data = json.loads(done.stdout)
    assert data["status"] == "solved" and data["engine"] == "aries"
    ride = next(s for s in data["steps"] if s["action"] == "ride_lift")
    assert {p["at"] for p in ride["after"]} == {"end"}
    assert len(ride["after"]) == 2


def test_no_plan_exits_1_with_the_reason_on_one_line(dura: Dura, tmp_path: Path) -> None:
    problem = with_goal(tmp_path, ROOT_PROBLEM, "(picture_taken dock)")
    done = dura("plan", "--offline", str(USECASE_DOMAIN), str(problem), "--timeout", "5")
    assert done.returncode == 1
    assert done.stdout == ""
    (line,) = done.stderr.splitlines()
    assert line.startswith(f"dura: {problem}: no plan: kairos ")


def test_a_problem_with_an_error_is_one_line_with_file_and_line(dura: Dura, tmp_path: Path) -> None:
    problem = tmp_path / "bad.pddl"
    problem.write_text(
        "(define (problem p) (:domain usecase)\n (:objects a - place)\n (:init (robot_at b)))"
    )
    done = dura("plan", "--offline", str(USECASE_DOMAIN), str(problem))
    assert done.returncode == 1
    line, *excerpt = done.stderr.splitlines()
    assert line == f"dura: {problem}:3:19: unknown object 'b'"
    assert excerpt == ["    3 |  (:init (robot_at b)))", "      |                   ^"]
    json = dura("plan", "--offline", str(USECASE_DOMAIN), str(problem), "--json")
    assert json.returncode == 1
    assert json.stderr.splitlines() == [line]  # one line, for programs
    missing = dura("plan", "--offline", str(USECASE_DOMAIN), str(tmp_path / "nope.pddl"))
    assert missing.returncode == 1
    assert missing.stderr.splitlines() == [
        f"dura: {tmp_path / 'nope.pddl'}: cannot read: [Errno 2] No such file or directory: '{tmp_path / 'nope.pddl'}'"
    ]
    usage = dura("plan", "--offline", str(USECASE_DOMAIN), str(problem), "--engine", "nope")
    assert usage.returncode == 2
    assert len(usage.stderr.splitlines()) == 1
