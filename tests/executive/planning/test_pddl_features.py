"""The rest of temporal PDDL reaches the engine (issue 28): one small domain per feature
(``features/``), planned with ``dura plan --offline`` as a user runs it, and refused in
one line by an engine that lacks the feature, naming it and the engines that have it."""

from __future__ import annotations

import json
import subprocess
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest

FEATURES = Path(__file__).parent / "features"

Dura = Callable[..., subprocess.CompletedProcess[str]]


def files(feature: str) -> tuple[str, str]:
    return str(FEATURES / f"{feature}.domain.pddl"), str(FEATURES / f"{feature}.problem.pddl")


def plan(dura: Dura, feature: str, *more: str, problem: Path | None = None) -> dict[str, Any]:
    domain, own = files(feature)
    done = dura(
        "plan", "--offline", domain, str(problem or own), "--json", "--timeout", "20", *more
    )
    data: dict[str, Any] = json.loads(done.stdout)
    assert (done.returncode == 0) == (data["status"] == "solved"), done.stderr
    return data


def steps(data: dict[str, Any]) -> list[tuple[str, float, float | None]]:
    """(action(args), start, duration) of each step, by start."""
    out = [(f"{s['action']}({', '.join(s['args'])})", s["start"], s["duration"])
           for s in data["steps"]]  # fmt: skip
    return sorted(out, key=lambda s: s[1])


def refusal(dura: Dura, feature: str, engine: str) -> str:
    domain, problem = files(feature)
    done = dura("plan", "--offline", domain, problem, "--engine", engine, "--timeout", "20")
    assert done.returncode == 1
    (line,) = done.stderr.splitlines()
    where, found, rest = line.partition(f": no plan: {engine} does not support ")
    assert found and where.startswith("dura: ") and where.endswith(f"{feature}.problem.pddl")
    return rest


def test_a_constant_of_the_domain_is_planned_with(dura: Dura) -> None:
    data = plan(dura, "constants")
    assert data["engine"] == "kairos"  # auto: the first installed engine that supports it
    assert [s[0] for s in steps(data)] == ["go_home(r1, lab)", "charge(r1)"]


def test_an_engine_without_durative_actions_refuses_naming_them_and_who_has_them(
    dura: Dura,
) -> None:
    line = refusal(dura, "constants", "fast-downward")
    assert "durative actions (CONTINUOUS_TIME)" in line
    assert "(installed engines that do: kairos, aries" in line


def test_durations_are_computed_from_numeric_functions_and_bounded_by_inequalities(
    dura: Dura,
) -> None:
    data = plan(dura, "numeric")
    (a_b, b_c, scan) = steps(data)
    assert (a_b[0], a_b[2]) == ("drive(a, b)", 5.0)  # distance 10 at speed 2
    assert (b_c[0], b_c[2]) == ("drive(b, c)", 3.0)
    assert scan[0] == "scan(c)"
    assert scan[2] is not None and 1.0 <= scan[2] <= 4.0


def test_an_engine_without_real_numbers_refuses_the_numeric_domain(dura: Dura) -> None:
    line = refusal(dura, "numeric", "aries")
    assert "numeric functions (REAL_FLUENTS)" in line
    assert "(installed engines that do: kairos" in line


def test_negative_disjunctive_and_quantified_conditions_are_planned_with(dura: Dura) -> None:
    data = plan(dura, "conditions")
    labels = [s[0] for s in steps(data)]
    assert {"sweep(a)", "sweep(b)", "move(a, b)"} <= set(labels)
    assert labels[-1] == "finish()"  # every room clean or locked, c stays locked
    assert "move(a, c)" not in labels and "move(b, c)" not in labels


def test_an_engine_without_quantified_conditions_refuses_naming_them(dura: Dura) -> None:
    line = refusal(dura, "conditions", "aries")
    assert "existential conditions (EXISTENTIAL_CONDITIONS)" in line
    assert "universal conditions (UNIVERSAL_CONDITIONS)" in line
    assert "(installed engines that do: kairos" in line


def test_a_conditional_effect_reaches_the_goal(dura: Dura) -> None:
    data = plan(dura, "conditional")
    assert [s[0] for s in steps(data)] == ["load(big)"]  # only the heavy box makes it careful


def test_an_engine_without_conditional_effects_refuses_naming_them(dura: Dura) -> None:
    line = refusal(dura, "conditional", "aries")
    assert line == "conditional effects (CONDITIONAL_EFFECTS) (installed engines that do: kairos)"


def test_timed_initial_literals_of_a_problem_file_reach_the_engine(dura: Dura) -> None:
    ((label, start, duration),) = steps(plan(dura, "til"))
    assert label == "pass(hall, lab)"
    assert duration is not None
    assert start >= 10.0 and start + duration <= 30.0  # while the door is open


def test_an_engine_without_timed_initial_literals_refuses_naming_them(dura: Dura) -> None:
    line = refusal(dura, "til", "fast-downward")
    assert "timed initial literals (TIMED_EFFECTS)" in line
    assert "(installed engines that do: kairos, aries" in line


@pytest.mark.parametrize("engine", ["kairos", "aries"])
def test_the_metric_of_a_problem_file_makes_the_engine_take_the_cheap_roads(
    dura: Dura, engine: str
) -> None:
    data = plan(dura, "metric", "--engine", engine)
    assert [s[0] for s in steps(data)] == ["drive(a, b)", "drive(b, c)", "drive(c, d)"]
    assert data["notes"] == []


def test_without_the_metric_the_first_plan_takes_the_highway(dura: Dura, tmp_path: Path) -> None:
    _, problem = files("metric")
    text = Path(problem).read_text().replace("(:metric minimize (total-cost))", "")
    (tmp_path / "first.pddl").write_text(text)
    data = plan(dura, "metric", "--engine", "kairos", problem=tmp_path / "first.pddl")
    assert [s[0] for s in steps(data)] == ["speed(a, d)"]


def test_an_engine_that_does_not_optimise_plans_and_says_so(dura: Dura, tmp_path: Path) -> None:
    _, problem = files("metric")
    text = Path(problem).read_text()
    makespan = text.replace("(:metric minimize (total-cost))", "(:metric minimize (total-time))")
    (tmp_path / "fast.pddl").write_text(makespan.replace("(increase (total-cost) 1)", ""))
    domain = Path(files("metric")[0]).read_text()
    classical = domain.replace(" (increase (total-cost) 1)", "").replace(
        " (increase (total-cost) 100)", ""
    )
    (tmp_path / "classical.pddl").write_text(
        classical.replace("(:functions (total-cost))", "").replace(" :action-costs", "")
    )
    (tmp_path / "fast.pddl").write_text(makespan.replace(" (= (total-cost) 0)", ""))
    done = dura(
        "plan", "--offline", str(tmp_path / "classical.pddl"), str(tmp_path / "fast.pddl"),
        "--engine", "fast-downward", "--json",
    )  # fmt: skip
    data = json.loads(done.stdout)
    assert data["status"] == "solved", done.stderr
    (note,) = data["notes"]
    assert note.startswith("fast-downward does not optimise a makespan metric (MAKESPAN)")
    assert "engines that optimise it: kairos, aries" in note
