"""Programs not written with the SDK, driven by the process translator."""

from __future__ import annotations

import signal
from pathlib import Path

import psutil

from executive.bus.states import GoalStatus, Lifecycle
from executive.runtime.translator import load
from executive.runtime.translators.process import ProcessTranslator
from knowledge.description import ComponentSpec
from tests.conftest import wait_for
from tests.executive.runtime.rig import rig, robot, scripted

PLAIN = ("--", "python", "-m", "tests.executive.runtime.plain_program")


def translated(name: str, *args: str, behavior: bool = False) -> ComponentSpec:
    return scripted(
        name, "executive.runtime.translator", "process", *PLAIN, *args, behavior=behavior
    )


def program_of(pid: int | None) -> psutil.Process:
    """The plain program under a translator host."""
    assert pid is not None
    children = psutil.Process(pid).children()
    assert len(children) == 1
    return children[0]


def test_the_process_translator_is_registered_as_a_plug_in() -> None:
    assert load("process") is ProcessTranslator


def test_a_translated_program_starts_pauses_resumes_and_stops_with_its_host(
    endpoint: str, tmp_path: Path
) -> None:
    with rig(robot(translated("driver")), endpoint, tmp_path) as r:
        state = r.launcher.start("driver")
        assert state.state is Lifecycle.READY
        program = program_of(state.pid)
        assert "tests.executive.runtime.plain_program" in program.cmdline()
        assert wait_for(lambda: "plain program runs for 60 s" in r.launcher.logs("driver"))
        r.launcher.pause("driver")
        assert wait_for(lambda: program.status() == psutil.STATUS_STOPPED)
        r.launcher.resume("driver")
        assert wait_for(lambda: program.status() != psutil.STATUS_STOPPED)
        assert r.launcher.stop("driver").exit_code == 0
        assert not program.is_running()


def test_a_translated_program_that_dies_takes_its_host_along_the_same_way(
    endpoint: str, tmp_path: Path
) -> None:
    with rig(robot(translated("driver")), endpoint, tmp_path) as r:
        program = program_of(r.launcher.start("driver").pid)
        program.send_signal(signal.SIGKILL)
        assert r.states.wait(lambda p: p["state"] == "exited")
        assert r.launcher.state("driver").reason == "killed by SIGKILL (dura component logs driver)"


def test_a_translated_behavior_returns_its_programs_exit_code_as_the_result(
    endpoint: str, tmp_path: Path
) -> None:
    job = translated("job", "{seconds}", "{code}", behavior=True)
    with rig(robot(job), endpoint, tmp_path) as r:
        r.launcher.start("job")
        done = r.launcher.send_goal("job", {"seconds": 0.1, "code": 0}).wait(10)
        assert done is not None and done.status is GoalStatus.SUCCEEDED
        assert done.value == {"exit_code": 0}
        failed = r.launcher.send_goal("job", {"seconds": 0, "code": 5}).wait(10)
        assert failed is not None and failed.status is GoalStatus.FAILED
        assert failed.reason.endswith("exited with code 5")
        unfilled = r.launcher.send_goal("job", {"seconds": 0}).wait(10)
        assert unfilled is not None and unfilled.status is GoalStatus.FAILED
        assert "cannot fill in the program's arguments from the goal: 'code'" in unfilled.reason


def test_cancelling_a_translated_goal_ends_its_program(endpoint: str, tmp_path: Path) -> None:
    job = translated("job", "{seconds}", behavior=True)
    with rig(robot(job), endpoint, tmp_path) as r:
        host = r.launcher.start("job").pid
        handle = r.launcher.send_goal("job", {"seconds": 60})
        assert wait_for(lambda: len(psutil.Process(host).children()) == 1)
        program = program_of(host)
        handle.cancel()
        result = handle.wait(10)
        assert result is not None and result.status is GoalStatus.CANCELLED
        assert wait_for(lambda: not program.is_running())


def test_an_unknown_translator_fails_the_start_and_says_why(endpoint: str, tmp_path: Path) -> None:
    bad = scripted("driver", "executive.runtime.translator", "teleport", *PLAIN)
    with rig(robot(bad), endpoint, tmp_path) as r:
        state = r.launcher.start("driver")
        assert state.state is Lifecycle.FAILED
        assert state.reason == (
            "exited with code 1 before it was ready: dura translator: no translator 'teleport' "
            "(installed: process) (dura component logs driver)"
        )
        assert "dura translator: no translator 'teleport' (installed: process)" in r.launcher.logs(
            "driver"
        )
