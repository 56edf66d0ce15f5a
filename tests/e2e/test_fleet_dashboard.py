"""The dashboard of a fleet in a real browser (headless Chromium): the fleet's plan as a
Gantt chart with a row per robot, while two real robots carry it out."""

from __future__ import annotations

from pathlib import Path

import pytest

from executive.dashboard.server import Dashboard
from executive.fleet.description import load_fleet
from tests.e2e.test_fleet import depot
from tests.executive.dashboard.browser import Browser, chromium

pytestmark = pytest.mark.slow


def test_the_fleets_page_draws_its_plan_with_a_row_per_robot(tmp_path: Path) -> None:
    if chromium() is None:
        pytest.skip("no Chromium here: 'apt-get install chromium' (CI installs it)")
    with depot(tmp_path, ["r1", "r2"]) as (fleet, _):
        robot = load_fleet(fleet.description).as_robot()
        with (
            Dashboard.connect(
                robot, fleet.endpoint, port=0, folders=[fleet.folder], fleet=True
            ) as page,
            Browser() as browser,
        ):
            browser.open(page.url)
            fleet.submit_goal("(crate_at parcel1 lab)")
            fleet.submit_goal("(crate_at parcel2 office)")
            rows = browser.wait_for(
                "(() => { const r = [...document.querySelectorAll('#plan-chart text.robot')]"
                ".map(t => t.textContent); return r.length > 1 ? r : null; })()",
                90,
            )
            assert rows == ["r1", "r2"]
            steps = browser.evaluate(
                "[...document.querySelectorAll('#plan-chart g.step')]"
                ".map(g => [g.dataset.robot, g.dataset.label])"
            )
            assert steps and all(f"({robot}," in label for robot, label in steps)
            assert {robot for robot, _ in steps} == {"r1", "r2"}
            # the fleet has no components or observers of its own: those views are its
            # robots' (their dashboards), and the fleet asks its high level nothing else
            shown = browser.evaluate(
                "['goals-view', 'plan-view', 'events-view', 'components-view', "
                "'observations-view'].map(v => document.getElementById(v).offsetParent "
                "!== null)"
            )
            assert shown == [True, True, True, False, False]
            assert browser.evaluate("document.getElementById('link').textContent") == "live"
