"""The use case's robot driving on lidar, and the dashboard's lidar node watched in the
browser: for the browser tests and ``tests/benchmarks/dashboard.py``."""

from __future__ import annotations

import time

from executive.bus.api import planning, tasks
from executive.testing.harness import RobotProcess
from tests.executive.dashboard.browser import Browser

LIDAR_NODE = "document.querySelector('#graph g.node[data-node=\"lidar\"]')"
LIDAR_FAULTY = "window.lidarFaulty"  # when the page first drew lidar faulty (ms, epoch)


def driving_on_lidar(robot: RobotProcess) -> bool:
    return any(
        t.behavior == "move_to" and t.state == "running" and "lidar" in t.functionalities
        for t in tasks.TASK_LIST.call(robot.bus).tasks
    )


def drive(robot: RobotProcess, timeout: float = 90.0) -> None:
    """Wait until move_to drives on lidar, giving the robot somewhere to go if idle."""
    deadline = time.monotonic() + timeout
    places = ["office", "dock", "lab"]
    while not driving_on_lidar(robot):
        assert time.monotonic() < deadline, "move_to never drove on lidar"
        goals = planning.GOAL_LIST.call(robot.bus).goals
        if not any(g.state.is_open for g in goals):
            here = robot.facts("robot_at")
            there = next(p for p in places if f"(robot_at {p})" not in here)
            robot.submit_goal(f"(robot_at {there})")
        time.sleep(0.2)


def watch_lidar(browser: Browser) -> None:
    """From now on, note in :data:`LIDAR_FAULTY` when the page first draws lidar faulty
    (the page must not show it faulty now)."""
    browser.wait_for(f"!{LIDAR_NODE} || {LIDAR_NODE}.dataset.state !== 'faulty'", 60.0)
    browser.evaluate(
        f"{LIDAR_FAULTY} = null;"
        "if (!window.lidarWatch) window.lidarWatch = new MutationObserver(() => {"
        f"  const node = {LIDAR_NODE};"
        f"  if (node && node.dataset.state === 'faulty' && !{LIDAR_FAULTY})"
        f"    {LIDAR_FAULTY} = Date.now();"
        "});"
        "window.lidarWatch.observe(document.getElementById('graph'),"
        " {childList: true, subtree: true, attributes: true});"
    )
