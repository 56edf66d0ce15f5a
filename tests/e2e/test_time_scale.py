"""Robot time ten times faster than the wall clock runs the transport robot's delivery
as it runs in real time: the same events, in the same order.

What the scale cannot shorten (starting component processes, planning) takes the same
wall time at any scale, so two steps that run side by side may end in another order
relative to each other; every order the plan imposes is the same. The speed-up itself
is measured by ``python -m tests.benchmarks.high_level`` (no timing assertions here).
"""

from __future__ import annotations

from collections import defaultdict
from collections.abc import Callable

import pytest

from executive.testing.harness import RobotProcess
from knowledge.records import Event
from tests.conftest import ROOT

pytestmark = pytest.mark.slow

TRANSPORT = ROOT / "examples" / "transport" / "robot.yaml"
PLAN_EVENTS = ("PLANNING", "PLAN_STORED", "PLAN_START", "DISPATCH", "START", "END", "FAIL",
               "CANCEL", "REPLAN")  # fmt: skip
STEP_EVENTS = ("DISPATCH", "START", "END", "FAIL", "CANCEL")
Start = Callable[..., RobotProcess]


def trace(events: list[Event]) -> list[tuple[str, str]]:
    """The planning, plan and goal events as (kind, subject), oldest first."""
    return [
        (e.kind, e.subject) for e in events if e.kind in PLAN_EVENTS or e.kind.startswith("GOAL_")
    ]


def orders(events: list[Event]) -> dict[str, list[str]]:
    """What the plan orders: the dispatches, the life of each step, the goals' states,
    and the plans (planning rounds, replans)."""
    out: defaultdict[str, list[str]] = defaultdict(list)
    for kind, subject in trace(events):
        if kind == "DISPATCH":
            out["dispatches"].append(subject)
        if kind in STEP_EVENTS:
            out[f"step {subject}"].append(kind)
        elif kind.startswith("GOAL_"):
            out[subject].append(kind)
        else:
            out["plans"].append(kind)
    return dict(out)


def deliver(robot: RobotProcess) -> list[Event]:
    goal = robot.submit_goal("(crate_at parcel lab)")
    robot.wait_for(goal, "achieved", timeout=240)
    events = robot.events()
    robot.stop()
    return events


def test_time_scale_ten_delivers_the_crate_with_the_same_events_in_the_same_order(
    dura_robot: Start,
) -> None:
    real = deliver(dura_robot(TRANSPORT, name="real_time"))
    fast = deliver(dura_robot(TRANSPORT, name="ten_times", time_scale=10.0))
    assert sorted(trace(fast)) == sorted(trace(real))  # the same events
    assert orders(fast) == orders(real)  # in the same order, wherever the plan orders them
    assert [e.data["time_scale"] for e in fast if e.kind == "EXECUTIVE_STARTED"] == [10.0]
