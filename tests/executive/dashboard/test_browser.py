"""The dashboard of the thesis use case in a real browser (Debian's headless Chromium over
the DevTools protocol), and the pictures of a running robot on the command line.

One robot runs for the whole module: it works on its goals while the tests look at it.
"""

from __future__ import annotations

import json
import re
import subprocess
import threading
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import pytest

from executive.bus.api import planning
from executive.bus.keys import DIAGNOSES
from executive.bus.message import Message
from executive.dashboard.server import Dashboard
from executive.testing.harness import RobotProcess
from tests.conftest import USECASE
from tests.executive.dashboard.browser import Browser, chromium
from tests.executive.dashboard.driving import LIDAR_FAULTY, drive, watch_lidar
from tests.executive.dashboard.pictures import groups, parse

pytestmark = pytest.mark.slow

PICTURES = "(and (picture_taken lab) (picture_taken office))"
Dura = Callable[..., subprocess.CompletedProcess[str]]


@pytest.fixture(scope="module")
def robot(tmp_path_factory: pytest.TempPathFactory) -> Iterator[RobotProcess]:
    with RobotProcess(USECASE, tmp_path_factory.mktemp("robot")) as running:
        running.submit_goal(PICTURES, priority=1)
        yield running


@pytest.fixture(scope="module")
def dashboard(robot: RobotProcess) -> Iterator[Dashboard]:
    with Dashboard.connect(robot.robot, robot.endpoint, port=0, folders=[robot.folder]) as page:
        yield page


@pytest.fixture(scope="module")
def browser(dashboard: Dashboard) -> Iterator[Browser]:
    if chromium() is None:
        pytest.skip("no Chromium here: 'apt-get install chromium' (CI installs it)")
    with Browser() as opened:
        opened.open(dashboard.url)
        yield opened


def js(value: str) -> str:
    return json.dumps(value)


def test_the_page_shows_the_goals_the_plan_and_the_component_graph(
    robot: RobotProcess, browser: Browser
) -> None:
    browser.wait_for(
        "[...document.querySelectorAll('#goal-table td.expr')]"
        f".some(td => td.textContent === {js(PICTURES)})"
    )
    browser.wait_for("document.querySelectorAll('#plan-chart g.step').length > 0", 60)
    plan = planning.PLAN_SHOW.call(robot.bus).plan
    assert plan is not None
    drawn = browser.wait_for(
        "(() => { const s = [...document.querySelectorAll('#plan-chart g.step')]"
        ".map(g => g.dataset.label); return s.length ? s : null; })()"
    )
    assert drawn == [f"{s.action}({', '.join(s.args)})" for s in plan.steps]
    nodes = browser.evaluate(
        "[...document.querySelectorAll('#graph g.node')].map(g => g.dataset.node)"
    )
    assert {"lidar", "lidar_filter", "cam", "cam_to_lidar", "robot_base", "move_to",
            "take_picture", "obstacle_scan", "scan"} <= set(nodes)  # fmt: skip
    assert browser.evaluate("document.getElementById('link').textContent") == "live"
    browser.pump(0.2)
    assert browser.errors == []


def test_a_goal_added_on_the_page_reaches_the_executive(
    robot: RobotProcess, browser: Browser
) -> None:
    submit = (
        "document.getElementById('goal-expression').value = {expression};"
        "document.getElementById('goal-priority').value = '2';"
        "document.getElementById('goal-form').requestSubmit();"
    )
    browser.evaluate(submit.format(expression=js("(robot_at lab)")))
    said = browser.wait_for(
        "(() => { const m = document.getElementById('goal-message');"
        " return m.classList.contains('ok') ? m.textContent : null; })()"
    )
    assert "added: (robot_at lab)" in said
    goals = planning.GOAL_LIST.call(robot.bus).goals
    added = [g for g in goals if g.expression == "(robot_at lab)"]
    assert len(added) == 1 and added[0].priority == 2 and added[0].source == "user"
    browser.evaluate(submit.format(expression=js("(picture_taken lob)")))
    refused = browser.wait_for(
        "(() => { const m = document.getElementById('goal-message');"
        " return m.classList.contains('error') ? m.textContent : null; })()"
    )
    assert "unknown object 'lob'" in refused
    browser.pump(0.2)
    # the refusal is an HTTP 400, which the browser logs; nothing else may be there
    assert len(browser.errors) == 1 and "status of 400" in browser.errors[0]
    assert "/api/goals" in browser.errors[0]
    browser.errors.clear()


def test_a_lidar_fault_turns_lidars_node_faulty_on_the_page(
    robot: RobotProcess, browser: Browser
) -> None:
    """How soon: ``python -m tests.benchmarks.dashboard`` (within 2 s of the diagnosis)."""
    drive(robot)
    watch_lidar(browser)
    diagnosed = threading.Event()

    def on_diagnosis(message: Message) -> None:
        if ["lidar"] in message.payload.get("diagnoses", []):
            diagnosed.set()

    robot.bus.subscribe(DIAGNOSES, on_diagnosis)
    robot.inject_fault("lidar", "stop_publishing")
    assert diagnosed.wait(20.0), "the executive never diagnosed lidar"
    browser.wait_for(LIDAR_FAULTY, timeout=20.0)
    browser.wait_for(
        "Number(document.querySelector('#graph g.node[data-node=\"lidar\"]')"
        ".dataset.faults || 0) >= 1",
        timeout=10.0,
    )
    browser.pump(0.2)
    assert browser.errors == []


def test_plan_show_draws_the_running_robots_plan(
    robot: RobotProcess, dura: Dura, tmp_path: Path
) -> None:
    picture = tmp_path / "plan.svg"
    done = dura("plan", "show", "--robot", str(USECASE), "--endpoint", robot.endpoint,
                "--svg", str(picture), env=robot.environment())  # fmt: skip
    assert done.returncode == 0, done.stderr
    plan = planning.PLAN_SHOW.call(robot.bus).plan
    assert plan is not None
    rows = groups(parse(picture.read_text()), "step")
    assert [r.get("data-label") for r in rows] == [
        f"{s.action}({', '.join(s.args)})" for s in plan.steps
    ]
    assert {r.get("data-state") for r in rows} <= {"pending", "dispatched", "running", "paused",
                                                   "done", "failed", "cancelled"}  # fmt: skip


def test_graph_with_diagnoses_draws_the_running_robots_state(
    robot: RobotProcess, dura: Dura, tmp_path: Path
) -> None:
    picture = tmp_path / "graph.svg"
    done = dura("graph", str(USECASE), "--endpoint", robot.endpoint, "--diagnoses",
                "--svg", str(picture), env=robot.environment())  # fmt: skip
    assert done.returncode == 0, done.stderr
    states: dict[str, Any] = {
        g.get("data-node"): g.get("data-state")
        for g in groups(parse(picture.read_text()), "node")
        if g.get("data-kind") in ("functionality", "behavior")
    }
    assert set(states) == set(robot.robot.components)
    assert set(states.values()) <= {"running", "starting", "stopping", "paused", "stopped",
                                    "faulty", "permanently faulty"}  # fmt: skip


def test_the_page_rounds_measured_values_and_draws_the_plan_s_title_once(
    robot: RobotProcess, browser: Browser
) -> None:
    values = browser.wait_for(
        "(() => { const v = [...document.querySelectorAll('#observation-table tbody tr')]"
        ".map(r => r.cells[3] && r.cells[3].textContent).filter(t => t);"
        " return v.length ? v : null; })()",
        30,
    )
    shown = [pair for cell in values for pair in cell.split(", ")]
    assert shown and all(re.fullmatch(r"\w+ -?\d+(\.\d{1,2})?", pair) for pair in shown), shown
    browser.wait_for("document.querySelectorAll('#plan-chart g.step').length > 0", 60)
    title = browser.evaluate("document.getElementById('plan-title').textContent")
    drawn = browser.evaluate(
        "[...document.querySelectorAll('#plan-chart text')].map(t => t.textContent)"
    )
    assert title.startswith("plan ") and title not in drawn


def test_the_badge_says_live_only_over_a_full_page_and_an_old_failure_is_grey(
    browser: Browser,
) -> None:
    browser.wait_for("document.getElementById('link').textContent === 'live'", 30)
    # a page that has not yet had its plan (the stream just opened) is not "live"
    loading = browser.evaluate(
        "(() => { page.loaded.delete('plan'); showLink();"
        " const said = document.getElementById('link').textContent;"
        " page.loaded.add('plan'); showLink(); return said; })()"
    )
    assert loading == "loading…"
    assert browser.evaluate("document.getElementById('link').textContent") == "live"
    row = (
        "(() => { const now = Date.now() / 1000 - page.clockSkew;"
        " page.tracks.set('probe', {key: 'probe', observer: 'probe', type: 'timeout',"
        " resource: ['scan'], callerids: [], observation: -4, message: 'timeout', verbose: '',"
        " values: {}, history: [], stamp: now - AGE}); drawObservations();"
        " const r = document.querySelector('#observation-table tr[data-observer=\"probe\"]');"
        " const seen = [r.dataset.failed, r.className];"
        " page.tracks.delete('probe'); drawObservations(); return seen; })()"
    )
    assert browser.evaluate(row.replace("AGE", "1")) == ["yes", ""]
    assert browser.evaluate(row.replace("AGE", "115")) == ["no", "stale"]  # no red row for it
