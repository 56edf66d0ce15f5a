"""The planner adapter: real engines in a worker process, validated plans, hard timeouts."""

from __future__ import annotations

import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import pytest

from executive.planning.goals import GoalSpec
from executive.planning.planner import TMP_PREFIX, Planner, PlanningTask, PlanStatus, engine_names
from executive.planning.problem import World
from knowledge.errors import PlanningError
from tests.conftest import ROOT
from tests.executive.planning.planning_cases import (
    CLASSICAL_DOMAIN,
    CLASSICAL_PROBLEM,
    TRANSPORT_DOMAIN,
    TRANSPORT_PROBLEM,
    USECASE_DOMAIN,
    expr,
    kairos_fixture,  # noqa: F401 (a fixture)
    usecase_task,
    world,
)


def test_kairos_plans_the_use_case_and_an_independent_validator_accepts_the_plan(
    kairos: Planner,
) -> None:
    result = kairos.solve(
        usecase_task("(picture_taken lab)", "(picture_taken office)", "(robot_at dock)")
    )
    assert result.status is PlanStatus.SOLVED, result.log
    assert result.engine == "kairos"
    assert result.validator in ("up_time_triggered_validator", "kairos-val")
    assert result.plan is not None
    labels = [s.label for s in result.plan.steps]
    assert {"take_picture(lab)", "take_picture(office)"} <= set(labels)
    assert result.plan.steps[-1].action == "move_to" and result.plan.steps[-1].args[1] == "dock"


def test_a_deadline_is_planned_for(kairos: Planner) -> None:
    # office by 7.5 s: drive there first (5 s) and take the picture (2 s)
    result = kairos.solve(
        usecase_task(("(picture_taken office)", {"deadline": 7.5}), "(picture_taken lab)")
    )
    assert result.ok and result.plan is not None
    picture = next(s for s in result.plan.steps if s.label == "take_picture(office)")
    assert picture.start + (picture.duration or 0) <= 7.5
    assert not any(s.action.startswith("dura_") for s in result.plan.steps)


def test_a_deadline_that_cannot_be_met_gives_no_plan(kairos: Planner) -> None:
    result = kairos.solve(usecase_task(("(picture_taken office)", {"deadline": 5.0})))
    assert result.status.no_plan, result.status


def test_no_plan_is_a_result_with_a_reason_not_an_exception(kairos: Planner) -> None:
    result = kairos.solve(usecase_task("(picture_taken dock)"))
    assert result.status.no_plan
    assert result.plan is None
    assert result.reason.startswith("kairos ")


def test_a_world_that_does_not_fit_the_domain_is_an_error_result(kairos: Planner) -> None:
    task = PlanningTask(USECASE_DOMAIN, World({"moon": "planet"}), ())
    result = kairos.solve(task)
    assert result.status is PlanStatus.ERROR
    assert "object 'moon' has unknown type 'planet'" in result.reason


def test_aries_plans_the_transport_domain_with_concurrent_steps(tmp_path: Path) -> None:
    goal = GoalSpec(
        1, expr("(and (crate_at parcel lab) (robot_at dock))", TRANSPORT_DOMAIN, TRANSPORT_PROBLEM)
    )
    task = PlanningTask(TRANSPORT_DOMAIN, world(TRANSPORT_DOMAIN, TRANSPORT_PROBLEM), (goal,))
    with Planner("aries", timeout=20) as aries:
        result = aries.solve(task)
        private = aries._tmp
    assert result.ok, result.log
    assert result.plan is not None
    first = {s.label for s in result.plan.roots()}
    assert first == {"drive(dock, store)", "call_lift(hall1, hall0)"}
    assert private is not None and not private.exists()  # Aries' temp files went with it


def test_aries_says_it_cannot_plan_with_real_numbers() -> None:
    with Planner("aries", timeout=5) as aries:
        result = aries.solve(usecase_task("(picture_taken lab)"))
    assert result.status is PlanStatus.UNSUPPORTED
    assert result.reason.startswith(
        "aries does not support real type durations (REAL_TYPE_DURATIONS)"
    )
    assert "installed engines that do: kairos" in result.reason


def test_fast_downward_plans_a_classical_domain(tmp_path: Path) -> None:
    domain = tmp_path / "rooms.pddl"
    domain.write_text(CLASSICAL_DOMAIN)
    problem = tmp_path / "tour.pddl"
    problem.write_text(CLASSICAL_PROBLEM)
    from executive.planning.problem import read_world

    rooms, goal = read_world(domain, problem)
    with Planner("fast-downward", timeout=20) as fd:
        result = fd.solve(PlanningTask(domain, rooms, (GoalSpec(1, goal),)))
    assert result.ok, result.log
    assert result.validator == "sequential_plan_validator"
    assert result.plan is not None
    assert [s.label for s in result.plan.steps] == ["go(a, b)", "go(b, c)", "go(c, a)"]
    assert all(s.duration is None for s in result.plan.steps)
    assert [[(p.step, p.at.value) for p in s.after] for s in result.plan.steps] == [
        [],
        [(0, "end")],
        [(1, "end")],
    ]


def test_an_unknown_engine_is_refused() -> None:
    with pytest.raises(PlanningError, match="unknown planner engine 'kiros'"):
        Planner("kiros")


SLEEPY = '''
import time
from unified_planning.engines import Engine
from unified_planning.engines.mixins.oneshot_planner import OneshotPlannerMixin


class SleepyEngine(Engine, OneshotPlannerMixin):
    """Ignores its timeout, like TAMER; starts a child process that would outlive it."""

    def __init__(self, **options):
        Engine.__init__(self)
        OneshotPlannerMixin.__init__(self)

    @property
    def name(self):
        return "sleepy"

    @staticmethod
    def supported_kind():
        from up_kairos.kind import SUPPORTED_KIND
        return SUPPORTED_KIND

    @staticmethod
    def supports(kind):
        return True

    def _solve(self, problem, heuristic=None, timeout=None, output_stream=None):
        import os, subprocess, sys
        child = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(600)"])
        with open(os.environ["SLEEPY_PIDS"], "w") as f:
            f.write(f"{os.getpid()} {child.pid}")
        time.sleep(600)
'''


def test_an_engine_that_ignores_its_timeout_is_killed_with_its_process_group(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    (tmp_path / "sleepy_engine.py").write_text(SLEEPY)
    info = tmp_path / "sleepy_engine-1.0.dist-info"
    info.mkdir()
    (info / "METADATA").write_text("Metadata-Version: 2.1\nName: sleepy-engine\nVersion: 1.0\n")
    (info / "entry_points.txt").write_text("[dura.planners]\nsleepy = sleepy_engine:SleepyEngine\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    monkeypatch.setenv("PYTHONPATH", str(tmp_path))
    pids = tmp_path / "pids"
    monkeypatch.setenv("SLEEPY_PIDS", str(pids))
    assert "sleepy" in engine_names()
    with Planner("sleepy", timeout=0.5) as sleepy:
        began = time.monotonic()
        result = sleepy.solve(usecase_task("(picture_taken lab)"))
        took = time.monotonic() - began
        assert result.status is PlanStatus.TIMEOUT
        assert "killed after" in result.reason
        assert took < 60
        for pid in map(int, pids.read_text().split()):
            assert gone(pid), f"process {pid} outlived the timeout"
        # the next job gets a fresh worker
        assert sleepy.solve(usecase_task("(picture_taken lab)")).status is PlanStatus.TIMEOUT


def gone(pid: int, wait: float = 10.0) -> bool:
    """Whether a process ended (a zombie waiting for its new parent to reap it counts)."""
    deadline = time.monotonic() + wait
    while time.monotonic() < deadline:
        try:
            state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
        except (FileNotFoundError, ProcessLookupError, IndexError):
            return True
        if state in ("Z", "X"):
            return True
        time.sleep(0.05)
    return False


def test_closing_a_planner_leaves_no_worker_and_no_temp_files(kairos: Planner) -> None:
    with Planner("kairos", timeout=5) as planner:
        assert planner.solve(usecase_task("(picture_taken lab)")).ok
        process, private = planner._process, planner._tmp
    assert process is not None and process.poll() is not None
    assert private is not None and not private.exists()
    assert gone(process.pid)


def test_a_new_worker_removes_the_folders_of_workers_killed_without_cleaning_up(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setattr(tempfile, "tempdir", str(tmp_path))
    ended = subprocess.Popen(["true"])
    ended.wait()

    def folder(name: str, pid: int | None, age: float = 0.0) -> Path:
        path = tmp_path / f"{TMP_PREFIX}{name}"
        path.mkdir()
        if pid is not None:
            (path / "worker.pid").write_text(str(pid))
        (path / "engine-output.txt").write_text("left over")
        os.utime(path, (time.time() - age, time.time() - age))
        return path

    dead = folder("dead", ended.pid)
    alive = folder("alive", os.getpid())
    old = folder("old", None, age=7200)
    young = folder("young", None)
    with Planner("kairos", timeout=5) as planner:
        planner.start()
        assert planner._tmp is not None and planner._tmp.parent == tmp_path
    assert not dead.exists() and not old.exists()
    assert alive.exists() and young.exists()


WARM_WORKER = """
import sys, tempfile
from pathlib import Path
from executive.planning.planner_worker import warm_up
warm_up(Path(tempfile.mkdtemp()) / "out.txt")
print("scipy" in sys.modules, "numpy" in sys.modules)
from unified_planning.engines import Engine
space = Engine.get_configuration_space()
print(type(space).__module__.split(".")[0], "scipy" in sys.modules)
"""


def test_a_warm_worker_has_not_loaded_configspace_but_gives_a_real_one_when_asked() -> None:
    done = subprocess.run(
        [sys.executable, "-c", WARM_WORKER], capture_output=True, text=True, timeout=120,
        env={**os.environ, "PYTHONPATH": str(ROOT)}, check=True,
    )  # fmt: skip
    warm, asked = done.stdout.splitlines()
    assert warm == "False False"  # unified-planning and the engines, without numpy/scipy
    assert asked == "ConfigSpace True"  # the real package, loaded on demand
