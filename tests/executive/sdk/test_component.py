"""The component SDK in real processes: lifecycle, commands, liveliness, faults."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

from executive.bus import keys
from executive.bus.keys import component, topic
from executive.bus.session import Bus
from executive.bus.states import Lifecycle
from executive.sdk import Behavior, Functionality, Message
from executive.sdk.fault_injection import Fault, FaultMode
from knowledge.description import ComponentSpec
from knowledge.errors import BusError, ComponentError
from tests.conftest import ROOT, USECASE, wait_for
from tests.executive.runtime.rig import Recorder, rig, robot, scripted, usecase


def probe(**params: object) -> ComponentSpec:
    return scripted("probe", "tests.executive.runtime.probe", params=params)


def test_the_hooks_run_in_lifecycle_order_with_their_arguments(
    endpoint: str, tmp_path: Path
) -> None:
    with rig(robot(probe(rate=5.0)), endpoint, tmp_path) as r:
        hooks = Recorder(r.bus, topic("probe/hooks"))
        r.kb.set_achievement("probe", "seen", 3)
        r.launcher.start("probe")
        r.launcher.pause("probe")
        r.launcher.resume("probe")
        r.launcher.reconfigure("probe", {"rate": 2.0})
        r.launcher.stop("probe")
        assert wait_for(lambda: len(hooks.payloads) == 6)
        assert [p["hook"] for p in hooks.payloads] == [
            "configure",
            "start",
            "pause",
            "resume",
            "reconfigure",
            "stop",
        ]
        configure = hooks.payloads[0]
        assert configure["params"] == {"rate": 5.0} and configure["achievements"] == {"seen": 3}
        assert hooks.payloads[4]["params"] == {"rate": 2.0}


def test_a_component_without_on_reconfigure_refuses_new_parameters_while_it_runs(
    endpoint: str, tmp_path: Path
) -> None:
    with rig(robot(usecase("cam")), endpoint, tmp_path) as r:
        r.launcher.start("cam")
        with pytest.raises(ComponentError, match=r"'cam' cannot change its parameters while it"):
            r.launcher.reconfigure("cam", {"rate": 5.0})
        assert r.launcher.state("cam").state is Lifecycle.READY


def test_a_rate_loop_changes_its_rate_while_it_runs(endpoint: str, tmp_path: Path) -> None:
    with rig(robot(usecase("lidar")), endpoint, tmp_path) as r:
        scans = Recorder(r.bus, topic("scan"))
        r.launcher.start("lidar")
        assert wait_for(lambda: scans.count() >= 5, 10)
        r.launcher.reconfigure("lidar", {"rate": 40.0})
        scans.clear()
        assert wait_for(lambda: scans.count() >= 41, 10)
        stamps = [m.payload["stamp"] for m in scans.messages][-40:]
        assert (len(stamps) - 1) / (stamps[-1] - stamps[0]) > 20.0  # well above 10 Hz


def test_an_exception_in_a_rate_loop_ends_the_component_with_exit_code_1(
    endpoint: str, tmp_path: Path
) -> None:
    with rig(robot(probe(explode=True)), endpoint, tmp_path) as r:
        r.launcher.start("probe")
        assert r.states.wait(lambda p: p["state"] == "exited")
        assert r.launcher.state("probe").exit_code == 1
        assert any("RuntimeError: the probe explodes" in line for line in r.launcher.logs("probe"))


def test_sigterm_stops_a_component_gracefully(endpoint: str, tmp_path: Path) -> None:
    with rig(robot(probe()), endpoint, tmp_path) as r:
        hooks = Recorder(r.bus, topic("probe/hooks"))
        pid = r.launcher.start("probe").pid
        assert pid is not None
        os.kill(pid, signal.SIGTERM)
        assert r.states.wait(lambda p: p["state"] == "exited")
        assert r.launcher.state("probe").exit_code == 0
        assert hooks.wait(lambda p: p["hook"] == "stop")


@pytest.fixture
def lone_probe(endpoint: str) -> Iterator[tuple[Bus, subprocess.Popen[bytes]]]:
    """A probe process started by hand, next to a bus that plays the executive."""
    with Bus("testbot", name="executive", endpoint=endpoint, listen=True) as bus:
        tokens: list[str] = []
        bus.watch_alive(keys.component_alive("probe"), lambda key, _: tokens.append(key))
        env = {
            **os.environ,
            keys.ENV_ROBOT: "testbot",
            keys.ENV_COMPONENT: "probe",
            keys.ENV_ENDPOINT: endpoint,
            keys.ENV_INSTANCE: "lone",
        }
        process = subprocess.Popen(
            [sys.executable, "-m", "tests.executive.runtime.probe"],
            env=env,
            cwd=ROOT,
            stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL,
        )
        try:
            assert wait_for(lambda: tokens == ["alive/component/probe/lone"], 10)
            yield bus, process
        finally:
            process.kill()
            process.wait()


def test_commands_out_of_order_or_unknown_are_refused_with_the_reason(
    lone_probe: tuple[Bus, subprocess.Popen[bytes]],
) -> None:
    bus, _ = lone_probe
    cmd = component("probe", "cmd")
    with pytest.raises(BusError, match=r"^cannot start 'probe': it is created$"):
        bus.request(cmd, {"cmd": "start"})
    with pytest.raises(BusError, match=r"^unknown command 'dance' \(choose from configure, "):
        bus.request(cmd, {"cmd": "dance"})
    with pytest.raises(BusError, match=r"^'params' must be an object, not \[1\]$"):
        bus.request(cmd, {"cmd": "configure", "params": [1]})
    with pytest.raises(BusError, match="'probe' is a functionality: it takes no goals"):
        bus.request(cmd, {"cmd": "goal", "goal_id": "g", "goal": {}})
    assert bus.request(cmd, {"cmd": "configure", "params": {"rate": 4}}) == {"phase": "configured"}
    assert bus.request(cmd, {"cmd": "start"}) == {"phase": "running"}


def test_a_command_with_a_bad_field_is_refused_by_its_declared_type(
    lone_probe: tuple[Bus, subprocess.Popen[bytes]],
) -> None:
    bus, _ = lone_probe
    cmd = component("probe", "cmd")
    with pytest.raises(BusError, match=r"^'achievements' must be an object, not \"all\"$"):
        bus.request(cmd, {"cmd": "configure", "achievements": "all"})
    with pytest.raises(BusError, match=r"^'goal_id' must be a non-empty string, not null$"):
        bus.request(cmd, {"cmd": "cancel"})
    assert bus.request(cmd, {"cmd": "configure"}) == {"phase": "configured"}


def test_a_component_ends_when_the_executive_vanishes(
    lone_probe: tuple[Bus, subprocess.Popen[bytes]], endpoint: str
) -> None:
    bus, process = lone_probe
    with Bus("testbot", name="executive-token", endpoint=endpoint) as holder:
        holder.declare_alive(keys.EXECUTIVE_ALIVE)
        cmd = component("probe", "cmd")
        bus.request(cmd, {"cmd": "configure"})
        bus.request(cmd, {"cmd": "start"})
    assert process.wait(10) == 0


def test_a_component_started_by_hand_says_what_it_needs() -> None:
    env = {k: v for k, v in os.environ.items() if not k.startswith("DURA_")}
    done = subprocess.run(
        [sys.executable, "-m", "components.lidar"],
        cwd=USECASE.parent,
        env=env,
        capture_output=True,
        text=True,
        timeout=60,
        check=False,
    )
    assert done.returncode == 2
    assert "DURA_ROBOT, DURA_COMPONENT, DURA_ENDPOINT not set" in done.stderr


# --- hooks and the framework ------------------------------------------------------------


@pytest.mark.parametrize(
    ("method", "hook"),
    [
        ("configure", "on_configure"),
        ("start", "on_start"),
        ("pause", "on_pause"),
        ("resume", "on_resume"),
        ("reconfigure", "on_reconfigure"),
        ("stop", "on_stop"),
        ("run", "on_start"),
        ("main", "on_start"),
        ("run_process", "on_start"),
    ],
)
def test_a_component_that_defines_a_framework_method_is_refused_with_the_hook_to_override(
    method: str, hook: str
) -> None:
    def defined(self: object) -> None:
        pass

    for base in (Functionality, Behavior):
        with pytest.raises(TypeError) as refused:
            type("Lidar", (base,), {method: defined})
        assert str(refused.value) == f"Lidar defines {method}(): override {hook}() instead"


def test_a_behavior_that_takes_goals_itself_is_told_to_override_execute() -> None:
    with pytest.raises(
        TypeError, match=r"^MoveTo defines take_goal\(\): override execute\(\) instead$"
    ):

        class MoveTo(Behavior):
            def execute(self, goal: dict[str, Any]) -> dict[str, Any]:
                return {}

            def take_goal(self, goal_id: str, goal: dict[str, Any]) -> None:
                pass

    with pytest.raises(
        TypeError,
        match=r"^Lidar defines cancel_goal\(\): goals are for a Behavior, which overrides execute\(\)$",
    ):

        class Lidar(Functionality):
            def on_start(self) -> None:
                pass

            def cancel_goal(self, goal_id: str) -> None:
                pass


def test_a_component_with_hooks_and_methods_of_its_own_is_accepted() -> None:
    class Base(Functionality):
        def on_configure(self, params: dict[str, Any], achievements: dict[str, Any]) -> None:
            pass

        def on_start(self) -> None:
            pass

        def command(self, message: Message) -> None:  # a topic handler, not the framework's
            pass

    class Spin(Base):
        def on_stop(self) -> None:
            pass

    assert Spin.kind.value == "functionality"


# --- faults ------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("spec", "message"),
    [
        ("melt", "unknown fault mode 'melt' (choose from crash, hang, "),
        ({"mode": "crash", "code": 2}, "unknown option 'code' for fault 'crash' (options: after"),
        ({"mode": "wrong_rate", "factor": "slow"}, "fault option 'factor' must be a number"),
    ],
)
def test_bad_fault_specifications_are_refused(spec: object, message: str) -> None:
    with pytest.raises(ComponentError) as error:
        Fault.parse(spec)
    assert str(error.value).startswith(message)


def test_a_fault_specification_names_its_mode_and_options() -> None:
    assert Fault.parse({"mode": "crash", "exit_code": 3, "after": 1}) == Fault(
        FaultMode.CRASH, after=1.0, exit_code=3
    )
    assert Fault.parse("slip") == Fault(FaultMode.SLIP)


def test_a_fault_parameter_strikes_after_its_delay(endpoint: str, tmp_path: Path) -> None:
    lidar = usecase("lidar", params={"rate": 10.0, "fault": {"mode": "crash", "after": 0.5}})
    with rig(robot(lidar), endpoint, tmp_path) as r:
        scans = Recorder(r.bus, topic("scan"))
        assert r.launcher.start("lidar").state is Lifecycle.READY
        assert r.states.wait(lambda p: p["state"] == "exited")
        assert r.launcher.state("lidar").exit_code == 1
        assert scans.count() > 0


def test_injected_faults_change_what_a_component_publishes(endpoint: str, tmp_path: Path) -> None:
    with rig(robot(usecase("lidar"), usecase("robot_base")), endpoint, tmp_path) as r:
        scans = Recorder(r.bus, topic("scan"))
        odom, imu = Recorder(r.bus, topic("odom")), Recorder(r.bus, topic("imu"))
        r.launcher.start("lidar")
        r.launcher.start("robot_base")

        r.launcher.inject_fault("lidar", "out_of_range")
        assert scans.wait(lambda p: set(p["ranges"]) == {-1.0})
        r.launcher.inject_fault("lidar", {"mode": "stale_timestamps", "age": 30})
        scans.clear()
        assert wait_for(lambda: scans.count() >= 3)
        assert all(m.received - m.payload["stamp"] > 25 for m in scans.messages[1:])
        r.launcher.inject_fault("lidar", "stop_publishing")
        scans.clear()
        assert not wait_for(lambda: scans.count() > 1, 0.5)
        r.launcher.inject_fault("lidar", "none")
        assert scans.wait(lambda p: min(p["ranges"]) > 0)

        r.launcher.inject_fault("robot_base", "slip")
        odom.clear()
        imu.clear()
        assert odom.wait(lambda p: p["linear"] == 0.5)
        assert imu.wait(lambda p: p["linear_velocity"] == 0.0)


def test_a_wrong_rate_fault_slows_the_rate_loops(endpoint: str, tmp_path: Path) -> None:
    with rig(robot(usecase("lidar", params={"rate": 20.0})), endpoint, tmp_path) as r:
        scans = Recorder(r.bus, topic("scan"))
        r.launcher.start("lidar")
        r.launcher.inject_fault("lidar", {"mode": "wrong_rate", "factor": 0.25})
        scans.clear()
        assert wait_for(lambda: scans.count() >= 6)
        stamps = [p["stamp"] for p in scans.payloads[1:6]]
        mean_period = (stamps[-1] - stamps[0]) / (len(stamps) - 1)
        assert mean_period > 0.1  # 0.2 s at the wrong rate; 0.05 s at the right one
