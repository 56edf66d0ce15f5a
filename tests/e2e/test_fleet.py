"""A fleet end to end: real executives (one per robot, each its own process and bus
login), real components on simulated hardware, a real planner, and the fleet's high
level (``dura fleet run``) running each step on the robot it names."""

from __future__ import annotations

import contextlib
import json
import subprocess
from collections.abc import Iterator, Sequence
from pathlib import Path

import pytest

from executive.bus.api.planning import STATE_GET, StateQuery
from executive.testing.fleet import FleetProcess, fleet_variant
from executive.testing.harness import RobotProcess, robot_variant
from knowledge.records import Event
from tests.conftest import ROOT, run_dura, wait_for

pytestmark = pytest.mark.slow

EXAMPLE = ROOT / "examples" / "fleet"
SCALE = 2.0  # robot time twice as fast as the wall clock: a drive takes 2.5 s


@contextlib.contextmanager
def depot(
    tmp_path: Path, names: Sequence[str]
) -> Iterator[tuple[FleetProcess, list[RobotProcess]]]:
    """The robots' executives, each in its own folder, and the fleet beside them."""
    with contextlib.ExitStack() as stack:
        robots = [
            stack.enter_context(
                RobotProcess(EXAMPLE / f"{name}.yaml", tmp_path / name, time_scale=SCALE)
            )
            for name in names
        ]
        path = fleet_variant(EXAMPLE / "fleet.yaml", robots, tmp_path, max_failures=2)
        fleet = stack.enter_context(FleetProcess(path, tmp_path / "fleet", time_scale=SCALE))
        yield fleet, robots


def steps_of(events: list[Event], kind: str, robot: str) -> list[str]:
    """The plan steps of one robot with an event of ``kind`` (``drive(r1, ...)``)."""
    return [e.subject for e in events if e.kind == kind and f"({robot}," in e.subject]


def test_two_robots_deliver_in_parallel_each_step_on_its_own_executive(tmp_path: Path) -> None:
    with depot(tmp_path, ["r1", "r2"]) as (fleet, (r1, r2)):
        # an operator's commands reach the fleet as they reach a robot: --fleet names it
        added = run_dura("goal", "add", "(crate_at parcel1 lab)", "--fleet", "../fleet.yaml",
                         "--endpoint", fleet.endpoint, "--json", cwd=fleet.folder)  # fmt: skip
        assert added.returncode == 0, added.stderr
        first = int(json.loads(added.stdout)["id"])
        second = fleet.submit_goal("(crate_at parcel2 office)")
        fleet.wait_for(first, "achieved", timeout=120)
        fleet.wait_for(second, "achieved", timeout=120)
        events = fleet.events()
        ended = {robot: steps_of(events, "END", robot) for robot in ("r1", "r2")}
        assert ended["r1"] and ended["r2"]  # both robots worked
        # each step ran on the executive of the robot it names, and only there
        for robot, process in (("r1", r1), ("r2", r2)):
            ran = [e.subject for e in process.events("TASK_SUCCEEDED")]
            assert len(ran) == len(ended[robot])
            assert all(f"({robot}," in subject for subject in ran)
        # in parallel: each robot's first step started before the other's last one ended
        kinds = [(e.kind, e.subject) for e in events]
        starts = {r: kinds.index(("START", steps_of(events, "START", r)[0])) for r in ended}
        ends = {r: kinds.index(("END", ended[r][-1])) for r in ended}
        assert starts["r1"] < ends["r2"] and starts["r2"] < ends["r1"]

        shown = run_dura("plan", "show", "--json", cwd=fleet.folder)  # the fleet's run file
        assert shown.returncode == 0, shown.stderr
        plan = json.loads(shown.stdout)
        assert plan["robots"] == [step["args"][0] for step in plan["plan"]["steps"]]
        status = json.loads(run_dura("status", "--json", cwd=fleet.folder).stdout)
        assert status["robots"] == [
            {"robot": "r1", "available": True, "reason": ""},
            {"robot": "r2", "available": True, "reason": ""},
        ]
        listed = json.loads(run_dura("events", "--json", "-n", "500", cwd=fleet.folder).stdout)
        dispatched = [e for e in listed["events"] if e["kind"] == "DISPATCH"]
        assert dispatched and all(e["data"]["robot"] == e["data"]["args"][0] for e in dispatched)

        # each robot's battery, as its own sensing rule measures it, is in the fleet's world
        def drained() -> set[str]:
            return {f.split()[2].rstrip(")") for f in fleet.facts("battery") if "100)" not in f}

        assert wait_for(lambda: drained() == {"r1", "r2"}, 30), fleet.facts("battery")
        assert sorted(fleet.facts("crate_at")) == [
            "(crate_at parcel1 lab)",
            "(crate_at parcel2 office)",
            "(crate_at parcel3 store)",
        ]


def test_a_robot_killed_mid_step_has_its_goal_finished_by_another_and_takes_work_when_back(
    tmp_path: Path,
) -> None:
    with depot(tmp_path, ["r1", "r2"]) as (fleet, robots):
        by_name = {r.robot.name: r for r in robots}
        goal = fleet.submit_goal("(crate_at parcel1 lab)")
        started = fleet.wait_for_event("START", timeout=60)
        worker = next(name for name in by_name if f"({name}," in started.subject)
        other = next(name for name in by_name if name != worker)
        by_name[worker].kill()  # SIGKILL of its executive, mid-step
        fleet.wait_for(goal, "achieved", timeout=120)
        events = fleet.events()
        lost = [e for e in events if e.kind == "ROBOT_LOST"]
        assert [e.subject for e in lost] == [worker]
        after = [e for e in events[events.index(lost[0]) :] if e.kind == "END"]
        assert after and all(f"({other}," in e.subject for e in after)
        # nothing done twice: the parcel was dropped once, where the goal wanted it
        drops = [e.subject for e in events if e.kind == "END" and e.subject.startswith("drop")]
        assert drops == [f"drop({other}, parcel1, lab)"]
        assert "(crate_at parcel1 lab)" in fleet.facts("crate_at")

        # back: it joins again, and takes work when the other is gone
        by_name[worker].start()
        assert wait_for(lambda: len(fleet.events("ROBOT_JOINED")) >= 3, 30)
        by_name[other].stop()
        assert wait_for(lambda: len(fleet.events("ROBOT_LOST")) >= 2, 30)
        again = fleet.submit_goal("(crate_at parcel2 office)")
        fleet.wait_for(again, "achieved", timeout=120)
        events = fleet.events()
        assert f"drop({worker}, parcel2, office)" in steps_of(events, "END", worker)
        assert by_name[worker].events("TASK_SUCCEEDED")  # its new executive ran them


def test_a_goal_no_robot_can_reach_waits_for_a_robot_to_come_back(tmp_path: Path) -> None:
    with depot(tmp_path, ["r1"]) as (fleet, (r1,)):
        r1.kill()
        assert wait_for(lambda: fleet.events("ROBOT_LOST") != [], 30)
        goal = fleet.submit_goal("(crate_at parcel1 lab)")
        fleet.wait_for(goal, "unreachable", timeout=60)  # no robot can act: no plan
        assert fleet.events("DISPATCH") == []  # nothing was sent to a robot not there
        r1.start()
        fleet.wait_for(goal, "achieved", timeout=120)  # back: it takes the goal
        assert r1.events("TASK_SUCCEEDED")


def test_a_robot_object_fleet_yaml_does_not_list_is_refused_at_run_time(tmp_path: Path) -> None:
    with depot(tmp_path, ["r1"]) as (fleet, _):

        def add(name: str, kind: str) -> subprocess.CompletedProcess[str]:
            return run_dura("object", "add", name, kind, "--fleet", "../fleet.yaml",
                            "--endpoint", fleet.endpoint, cwd=fleet.folder)  # fmt: skip

        # it would have no executive to carry out the steps a plan gives it
        refused = add("r4", "robot")
        assert refused.returncode == 1
        assert refused.stderr.splitlines() == [
            "dura: object 'r4' of type 'robot' is no robot of fleet 'depot' (its robots:"
            " r1): a robot joins the fleet in fleet.yaml, with its description, and the"
            " fleet runs again"
        ]
        assert "r4" not in STATE_GET.call(fleet.bus, StateQuery("")).objects
        assert fleet.events("OBJECT_ADDED") == []
        # any other object is added; so is one that is there already (r2, in the problem)
        assert add("parcel4", "crate").returncode == 0
        assert add("r2", "robot").returncode == 0
        objects = STATE_GET.call(fleet.bus, StateQuery("")).objects
        assert (objects["parcel4"], objects["r2"]) == ("crate", "robot")


def test_a_robot_whose_steps_keep_failing_is_set_aside_and_another_takes_its_goal(
    tmp_path: Path,
) -> None:
    broken = {"behaviors": {"drive_to": {"command": ["python", "-c", "raise SystemExit(3)"],
                                         "max_restarts": 0}}}  # fmt: skip
    r1_description = robot_variant(EXAMPLE / "r1.yaml", tmp_path / "broken", broken)
    with (
        RobotProcess(r1_description, tmp_path / "r1", time_scale=SCALE) as r1,
        RobotProcess(EXAMPLE / "r2.yaml", tmp_path / "r2", time_scale=SCALE) as r2,
    ):
        path = fleet_variant(EXAMPLE / "fleet.yaml", [r1, r2], tmp_path, max_failures=2)
        with FleetProcess(path, tmp_path / "fleet", time_scale=SCALE) as fleet:
            r2.stop()  # only r1 can act: the plan is its
            assert wait_for(lambda: fleet.events("ROBOT_LOST") != [], 30)
            goal = fleet.submit_goal("(crate_at parcel1 lab)")
            set_aside = fleet.wait_for_event("ROBOT_LOST", "r1", timeout=120)
            assert set_aside.data["reason"].startswith("its last 2 steps failed")
            assert len(steps_of(fleet.events(), "FAIL", "r1")) == 2
            r2.start()
            fleet.wait_for(goal, "achieved", timeout=120)
            events = fleet.events()
            assert steps_of(events, "END", "r1") == []
            assert "drop(r2, parcel1, lab)" in steps_of(events, "END", "r2")
