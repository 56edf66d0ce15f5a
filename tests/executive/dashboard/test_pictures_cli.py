"""Pictures on the command line, as a user runs them: ``dura graph ROBOT.yaml --svg`` and
``dura plan --offline DOMAIN PROBLEM --svg`` (no robot running)."""

from __future__ import annotations

import subprocess
from collections.abc import Callable
from pathlib import Path

from tests.conftest import USECASE
from tests.executive.dashboard.pictures import groups, parse
from tests.executive.planning.planning_cases import USECASE_DOMAIN, USECASE_PROBLEM

Dura = Callable[..., subprocess.CompletedProcess[str]]


def test_dura_graph_draws_the_robots_components_capabilities_and_topics(
    dura: Dura, tmp_path: Path
) -> None:
    picture = tmp_path / "graph.svg"
    done = dura("graph", str(USECASE), "--svg", str(picture))
    assert done.returncode == 0, done.stderr
    drawn = {
        g.get("data-node"): g.get("data-kind") for g in groups(parse(picture.read_text()), "node")
    }
    assert drawn["lidar"] == "functionality" and drawn["move_to"] == "behavior"
    assert drawn["obstacle_scan"] == "capability" and drawn["scan_filtered"] == "topic"


def test_dura_graph_without_svg_prints_the_components_as_a_table(dura: Dura) -> None:
    done = dura("graph", str(USECASE))
    assert done.returncode == 0, done.stderr
    lines = done.stdout.splitlines()
    assert lines[0].split() == [
        "COMPONENT",
        "KIND",
        "PROVIDES",
        "REQUIRES",
        "PUBLISHES",
        "SUBSCRIBES",
    ]
    assert any(
        line.split()[:3] == ["cam_to_lidar", "functionality", "obstacle_scan"] for line in lines
    )


def test_dura_graph_to_stdout_prints_only_the_picture(dura: Dura) -> None:
    done = dura("graph", str(USECASE), "--svg", "-")
    assert done.returncode == 0, done.stderr
    assert groups(parse(done.stdout), "node")


def test_dura_plan_offline_draws_the_plan_as_a_gantt_chart(dura: Dura, tmp_path: Path) -> None:
    problem = tmp_path / "pictures.pddl"
    problem.write_text(
        USECASE_PROBLEM.read_text().replace("(:goal (and))", "(:goal (picture_taken lab))")
    )
    picture = tmp_path / "plan.svg"
    done = dura("plan", "--offline", str(USECASE_DOMAIN), str(problem), "--svg", str(picture))
    assert done.returncode == 0, done.stderr
    assert "steps, makespan" in done.stdout  # the table is printed as before
    rows = groups(parse(picture.read_text()), "step")
    labels = [r.get("data-label") for r in rows]
    assert labels[-1] == "take_picture(lab)" and labels[0].startswith("move_to(")
    assert {r.get("data-state") for r in rows} == {"pending"}
