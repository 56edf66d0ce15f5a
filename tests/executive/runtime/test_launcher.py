"""The launcher with real component processes, a real bus and a real knowledge base."""

from __future__ import annotations

import contextlib
import os
import signal
import sys
import threading
from collections.abc import Iterator
from pathlib import Path

import psutil
import pytest

from executive.bus.keys import topic
from executive.bus.payloads import ComponentState
from executive.bus.states import GoalStatus, Lifecycle
from knowledge.description import FunctionalitySpec
from knowledge.errors import ComponentError
from tests.conftest import wait_for
from tests.executive.runtime.rig import Recorder, Rig, rig, robot, scripted, states, usecase


def gone(pid: int | None) -> bool:
    """Whether a process no longer exists (reaped: not even a zombie)."""
    assert pid is not None
    return not psutil.pid_exists(pid)


def test_a_started_component_is_ready_publishes_and_is_reported(
    endpoint: str, tmp_path: Path
) -> None:
    with rig(robot(usecase("lidar")), endpoint, tmp_path) as r:
        scans = Recorder(r.bus, topic("scan"))
        state = r.launcher.start("lidar")
        assert state.state is Lifecycle.READY and state.pid is not None
        assert scans.wait(lambda p: p["seq"] >= 3 and isinstance(p["stamp"], float))
        assert scans.messages[0].caller_id == "lidar"
        assert wait_for(lambda: states(r.states, "lidar") == ["starting", "ready"])
        assert r.launcher.state("lidar") == state
        assert wait_for(lambda: len(r.kb.events(kind="COMPONENT_READY")) == 1)
        assert r.kb.events(kind="COMPONENT_READY")[0].data["pid"] == state.pid


def test_starting_a_running_component_leaves_it_as_it_is(endpoint: str, tmp_path: Path) -> None:
    with rig(robot(usecase("lidar")), endpoint, tmp_path) as r:
        first = r.launcher.start("lidar")
        assert r.launcher.start("lidar") == first


def test_a_stopped_component_exits_cleanly_and_is_reaped(endpoint: str, tmp_path: Path) -> None:
    with rig(robot(usecase("lidar")), endpoint, tmp_path) as r:
        pid = r.launcher.start("lidar").pid
        state = r.launcher.stop("lidar")
        assert (state.state, state.exit_code, state.signal) == (Lifecycle.STOPPED, 0, None)
        assert gone(pid)
        assert wait_for(
            lambda: states(r.states, "lidar") == ["starting", "ready", "stopping", "stopped"]
        )
        assert r.launcher.stop("lidar") == state


def test_a_killed_component_is_reported_exited_with_its_signal(
    endpoint: str, tmp_path: Path
) -> None:
    with rig(robot(usecase("lidar")), endpoint, tmp_path) as r:
        pid = r.launcher.start("lidar").pid
        assert pid is not None
        os.kill(pid, signal.SIGKILL)
        assert r.states.wait(lambda p: p["state"] == "exited")
        state = ComponentState.from_payload(r.states.payloads[-1])
        assert (state.signal, state.exit_code, state.reason) == (
            9,
            None,
            "killed by SIGKILL (dura component logs lidar)",
        )
        assert gone(pid)
        assert wait_for(lambda: r.kb.events(kind="COMPONENT_EXITED") != [])
        assert r.kb.events(kind="COMPONENT_EXITED")[0].data["signal"] == 9


def test_a_crash_fault_is_reported_with_its_exit_code(endpoint: str, tmp_path: Path) -> None:
    with rig(robot(usecase("lidar")), endpoint, tmp_path) as r:
        r.launcher.start("lidar")
        r.launcher.inject_fault("lidar", {"mode": "crash", "exit_code": 3})
        assert r.states.wait(lambda p: p["state"] == "exited")
        assert r.launcher.state("lidar").exit_code == 3
        assert r.launcher.state("lidar").reason.startswith("exited with code 3: ")
        assert r.launcher.state("lidar").reason.endswith(
            "injected fault: crash (dura component logs lidar)"
        )


def test_a_component_that_never_gets_ready_fails_at_its_startup_timeout(
    endpoint: str, tmp_path: Path
) -> None:
    silent = FunctionalitySpec(
        name="silent", command=("python", "-c", "import time; time.sleep(60)"), startup_timeout=0.5
    )
    with rig(robot(silent), endpoint, tmp_path, grace=0.5) as r:
        state = r.launcher.start("silent")
        assert state.state is Lifecycle.FAILED
        assert state.reason == "not ready within 0.5 s (no answer)"
        assert state.signal == signal.SIGTERM
        assert gone(state.pid)


def test_a_program_that_does_not_exist_fails_with_the_reason(endpoint: str, tmp_path: Path) -> None:
    missing = usecase("lidar", command=("no-such-program-for-dura",))
    with rig(robot(missing), endpoint, tmp_path) as r:
        state = r.launcher.start("lidar")
        assert state.state is Lifecycle.FAILED
        assert state.reason == "cannot run 'no-such-program-for-dura': No such file or directory"


def test_a_component_that_exits_during_start_up_fails_with_its_exit_code(
    endpoint: str, tmp_path: Path
) -> None:
    quitter = usecase("lidar", command=("python", "-c", "raise SystemExit(4)"))
    with rig(robot(quitter), endpoint, tmp_path) as r:
        state = r.launcher.start("lidar")
        assert (state.state, state.exit_code) == (Lifecycle.FAILED, 4)
        assert state.reason == "exited with code 4 before it was ready (dura component logs lidar)"
        assert state.output == ()  # it wrote nothing


def test_a_component_that_raises_during_start_up_says_its_exception_and_where_to_read_more(
    endpoint: str, tmp_path: Path
) -> None:
    raiser = usecase("lidar", command=("python", "-c", "{}['celsius']"))
    with rig(robot(raiser), endpoint, tmp_path) as r:
        state = r.launcher.start("lidar")
        assert (state.state, state.exit_code) == (Lifecycle.FAILED, 1)
        assert state.reason == (
            "exited with code 1 before it was ready: KeyError: 'celsius' "
            "(dura component logs lidar)"
        )
        assert state.output[-1] == "KeyError: 'celsius'"
        assert state.output[0].startswith('  File "<string>", line 1')
        assert wait_for(lambda: r.kb.events(kind="COMPONENT_FAILED") != [])
        assert r.kb.events(kind="COMPONENT_FAILED")[-1].data["output"][-1] == "KeyError: 'celsius'"


def test_a_bad_parameter_fails_the_start_with_the_components_message(
    endpoint: str, tmp_path: Path
) -> None:
    with rig(robot(usecase("lidar", params={"rate": "fast"})), endpoint, tmp_path) as r:
        state = r.launcher.start("lidar")
        assert state.state is Lifecycle.FAILED
        assert state.reason == (
            "configure failed: parameter 'rate' of 'lidar' must be a float, not 'fast'"
        )


def test_a_hung_component_is_killed_after_the_grace_periods(endpoint: str, tmp_path: Path) -> None:
    with rig(robot(usecase("lidar")), endpoint, tmp_path, grace=0.3) as r:
        scans = Recorder(r.bus, topic("scan"))
        r.launcher.start("lidar")
        r.launcher.inject_fault("lidar", "hang")
        assert scans.wait(lambda p: True)
        scans.clear()
        state = r.launcher.stop("lidar")
        assert (state.state, state.signal) == (Lifecycle.STOPPED, signal.SIGKILL)
        assert scans.count() <= 1  # it stopped publishing when it hung
        assert gone(state.pid)


def test_a_restart_runs_a_new_process_with_the_parameters_from_the_kb(
    endpoint: str, tmp_path: Path
) -> None:
    probe = scripted("probe", "tests.executive.runtime.probe", params={"rate": 5.0, "say": "hi"})
    with rig(robot(probe), endpoint, tmp_path) as r:
        hooks = Recorder(r.bus, topic("probe/hooks"))
        first = r.launcher.start("probe")
        r.kb.set_parameter("probe", "rate", 8.0)
        second = r.launcher.restart("probe")
        assert second.state is Lifecycle.READY and second.pid != first.pid
        configured = [p["params"] for p in hooks.payloads if p["hook"] == "configure"]
        assert configured == [{"rate": 5.0, "say": "hi"}, {"rate": 8.0, "say": "hi"}]
        assert wait_for(
            lambda: (
                states(r.states, "probe")
                == ["starting", "ready", "stopping", "stopped", "starting", "ready"]
            )
        )


def test_a_paused_component_publishes_nothing_until_resumed(endpoint: str, tmp_path: Path) -> None:
    with rig(robot(usecase("lidar")), endpoint, tmp_path) as r:
        scans = Recorder(r.bus, topic("scan"))
        r.launcher.start("lidar")
        assert r.launcher.pause("lidar").state is Lifecycle.PAUSED
        scans.clear()
        threading.Event().wait(0.5)
        assert scans.count() == 0
        assert r.launcher.resume("lidar").state is Lifecycle.READY
        assert scans.wait(lambda p: True)


def test_components_run_in_their_own_process_group_with_the_robots_environment(
    endpoint: str, tmp_path: Path
) -> None:
    with rig(robot(scripted("probe", "tests.executive.runtime.probe")), endpoint, tmp_path) as r:
        hooks = Recorder(r.bus, topic("probe/hooks"))
        pid = r.launcher.start("probe").pid
        assert hooks.wait(lambda p: p["hook"] == "start")
        started = next(p for p in hooks.payloads if p["hook"] == "start")
        # the component is its supervisor's child; the supervisor heads the group
        supervisor = psutil.Process(pid).parent()
        assert supervisor is not None and supervisor.ppid() == os.getpid()
        assert started["pid"] == pid and started["pgid"] == supervisor.pid != os.getpgid(0)
        assert "executive/runtime/supervisor.py" in " ".join(supervisor.cmdline())
        env = started["env"]
        assert env["DURA_ROBOT"] == "testbot" and env["DURA_COMPONENT"] == "probe"
        assert env["DURA_ENDPOINT"] == endpoint and env["DURA_KIND"] == "functionality"
        assert psutil.Process(pid).cwd() == str(r.robot.path.parent)


def test_component_output_goes_to_its_log_file(endpoint: str, tmp_path: Path) -> None:
    probe = scripted(
        "probe", "tests.executive.runtime.probe", params={"say": "hello from the probe"}
    )
    with rig(robot(probe), endpoint, tmp_path) as r:
        pid = r.launcher.start("probe").pid
        r.launcher.stop("probe")
        lines = r.launcher.logs("probe")
        assert lines[0].startswith("--- dura: started probe (supervisor pid ")
        assert any(line.startswith(f"--- dura: probe ready (pid {pid})") for line in lines)
        assert "hello from the probe" in lines
        assert lines[-1].startswith("--- dura: stopped: exited with code 0")
        assert r.launcher.log_path("probe") == str(tmp_path / "logs" / "probe.log")


def test_unknown_components_and_wrong_commands_are_refused(endpoint: str, tmp_path: Path) -> None:
    with rig(robot(usecase("lidar")), endpoint, tmp_path) as r:
        with pytest.raises(
            ComponentError, match=r"no component 'lidr' in robot 'testbot' \(lidar\)"
        ):
            r.launcher.start("lidr")
        with pytest.raises(ComponentError, match="'lidar' is stopped, not running"):
            r.launcher.inject_fault("lidar", "crash")
        with pytest.raises(ComponentError, match="cannot pause 'lidar': it is stopped"):
            r.launcher.pause("lidar")
        r.launcher.start("lidar")
        assert r.launcher.resume("lidar").state is Lifecycle.READY  # nothing to resume
        with pytest.raises(ComponentError, match="unknown fault mode 'melt'"):
            r.launcher.inject_fault("lidar", "melt")
        with pytest.raises(ComponentError, match="'lidar' is a functionality: it takes no goals"):
            r.launcher.send_goal("lidar", {})


def test_listeners_hear_every_change_in_order(endpoint: str, tmp_path: Path) -> None:
    heard: list[str] = []
    with rig(robot(usecase("lidar")), endpoint, tmp_path) as r:
        r.launcher.add_listener(lambda s: heard.append(f"{s.component}:{s.state.value}"))
        r.launcher.start("lidar")
        r.launcher.stop("lidar")
        assert wait_for(lambda: len(heard) == 4)
        assert heard == ["lidar:starting", "lidar:ready", "lidar:stopping", "lidar:stopped"]


# --- behaviors ---------------------------------------------------------------------------


def test_a_behavior_returns_its_result_which_is_stored_in_the_kb(
    endpoint: str, tmp_path: Path
) -> None:
    picture = usecase("take_picture", params={"duration": 0.2})
    with rig(robot(usecase("cam"), picture), endpoint, tmp_path) as r:
        r.launcher.start("cam")
        r.launcher.start("take_picture")
        handle = r.launcher.send_goal("take_picture", {"place": "kitchen"})
        result = handle.wait(10)
        assert result is not None and result.status is GoalStatus.SUCCEEDED
        assert result.value["place"] == "kitchen" and result.value["image_seq"] > 0
        stored = r.kb.return_values(component="take_picture")
        assert stored == [result.to_payload()]
        assert [e.kind for e in r.kb.events(kind="GOAL_RESULT_SUCCEEDED")] == [
            "GOAL_RESULT_SUCCEEDED"
        ]


def test_a_behavior_fails_its_goal_when_its_input_is_missing(endpoint: str, tmp_path: Path) -> None:
    picture = usecase("take_picture", params={"duration": 0.1, "image_timeout": 0.3})
    with rig(robot(usecase("cam"), picture), endpoint, tmp_path) as r:
        r.launcher.start("take_picture")
        result = r.launcher.send_goal("take_picture", {"place": "hall"}).wait(10)
        assert result is not None and result.status is GoalStatus.FAILED
        assert result.reason == "no image within 0.3 s"


MOVE = ("lidar", "lidar_filter", "robot_base")


@contextlib.contextmanager
def moving(endpoint: str, folder: Path, **params: float) -> Iterator[Rig]:
    """move_to and the components it needs, all started."""
    move = usecase("move_to", params=params)
    with rig(robot(*(usecase(n) for n in MOVE), move), endpoint, folder) as r:
        for name in (*MOVE, "move_to"):
            assert r.launcher.start(name).state is Lifecycle.READY
        yield r


def test_move_to_reports_feedback_and_forgets_its_achievements_when_done(
    endpoint: str, tmp_path: Path
) -> None:
    with moving(endpoint, tmp_path, duration=1.0) as r:
        commands = Recorder(r.bus, topic("cmd_vel"))
        progress: list[float] = []
        handle = r.launcher.send_goal("move_to", {"target": "kitchen"}, task_id=None)
        handle.add_feedback_listener(lambda f: progress.append(f["done"]))
        result = handle.wait(15)
        assert result is not None and result.status is GoalStatus.SUCCEEDED, result
        assert result.value == {"target": "kitchen", "reached": True}
        assert progress == sorted(progress) and progress[-1] == 1.0
        assert commands.wait(lambda p: p["linear"] == 0.0)  # it stops the base at the end
        assert r.kb.achievements("move_to") == {}


def test_move_to_fails_when_its_scan_stops(endpoint: str, tmp_path: Path) -> None:
    with moving(endpoint, tmp_path, duration=30.0, input_timeout=0.5) as r:
        handle = r.launcher.send_goal("move_to", {"target": "kitchen"})
        assert wait_for(lambda: handle.feedback.get("done", 0) > 0)
        r.launcher.stop("lidar")
        result = handle.wait(10)
        assert result is not None and result.status is GoalStatus.FAILED
        assert result.reason.startswith("no scan_filtered for ")


def test_a_paused_move_to_holds_still_and_then_finishes(endpoint: str, tmp_path: Path) -> None:
    with moving(endpoint, tmp_path, duration=1.0) as r:
        handle = r.launcher.send_goal("move_to", {"target": "hall"})
        assert wait_for(lambda: handle.feedback.get("done", 0) > 0.1)
        r.launcher.pause("move_to")
        held = handle.feedback["done"]
        threading.Event().wait(1.5)  # longer than the whole move and the input timeout
        assert not handle.done() and handle.feedback["done"] <= held + 0.1
        r.launcher.resume("move_to")
        result = handle.wait(10)
        assert result is not None and result.status is GoalStatus.SUCCEEDED


def test_a_restarted_move_to_warm_starts_from_its_achievements(
    endpoint: str, tmp_path: Path
) -> None:
    with moving(endpoint, tmp_path, duration=3.0) as r:
        handle = r.launcher.send_goal("move_to", {"target": "dock"})
        assert wait_for(lambda: "progress" in r.kb.achievements("move_to"), 10)
        r.launcher.inject_fault("move_to", "crash")
        result = handle.wait(10)
        assert result is not None and result.status is GoalStatus.FAILED
        assert result.reason.startswith("'move_to' exited with code 1: ")
        assert result.reason.endswith("injected fault: crash (dura component logs move_to)")
        stored = r.kb.achievements("move_to")["progress"]
        assert stored["job"] == "move to dock" and stored["done"] > 0
        assert r.launcher.restart("move_to").state is Lifecycle.READY
        again = r.launcher.send_goal("move_to", {"target": "dock"})
        assert wait_for(lambda: "done" in again.feedback)
        assert again.feedback["done"] > stored["done"]
        assert again.wait(10) is not None


def test_stopping_a_behavior_cancels_its_goal(endpoint: str, tmp_path: Path) -> None:
    with moving(endpoint, tmp_path, duration=30.0) as r:
        handle = r.launcher.send_goal("move_to", {"target": "dock"})
        assert wait_for(lambda: "done" in handle.feedback)
        r.launcher.stop("move_to")
        result = handle.wait(5)
        assert result is not None and result.status is GoalStatus.CANCELLED


def test_a_cancelled_goal_ends_and_the_behavior_takes_the_next(
    endpoint: str, tmp_path: Path
) -> None:
    with moving(endpoint, tmp_path, duration=30.0) as r:
        handle = r.launcher.send_goal("move_to", {"target": "dock"})
        with pytest.raises(ComponentError, match=f"busy with goal {handle.goal_id}"):
            r.launcher.send_goal("move_to", {"target": "hall"})
        handle.cancel()
        result = handle.wait(5)
        assert result is not None and result.status is GoalStatus.CANCELLED
        assert result.reason == "cancelled"
        assert not r.launcher.send_goal("move_to", {"target": "hall"}).done()


def test_python_in_a_command_is_this_interpreter(endpoint: str, tmp_path: Path) -> None:
    with rig(robot(usecase("lidar")), endpoint, tmp_path) as r:
        pid = r.launcher.start("lidar").pid
        assert psutil.Process(pid).exe() == os.path.realpath(sys.executable)
