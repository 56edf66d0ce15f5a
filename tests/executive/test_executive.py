"""``dura run`` and ``dura component`` through the real command line, in subprocesses."""

from __future__ import annotations

import contextlib
import json
import os
import signal
import subprocess
import sys
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import psutil
import pytest

from executive.bus import security
from executive.bus.keys import DIAGNOSES, EVENTS, component, service_alive, topic
from executive.bus.message import Message
from executive.bus.payloads import ComponentState
from executive.bus.security import Login
from executive.bus.session import Bus
from executive.bus.states import Lifecycle
from executive.testing.harness import RobotProcess
from tests.conftest import ROOT, USECASE, run_dura, wait_for
from tests.executive.runtime.rig import Recorder

COMPONENTS = (
    "lidar",
    "lidar_filter",
    "robot_base",
    "cam",
    "cam_to_lidar",
    "move_to",
    "take_picture",
)
RATES = {"scan": 10.0, "odom": 20.0, "imu": 20.0, "image": 15.0, "scan_filtered": 25.0}


def operator(folder: Path) -> Login | None:
    """The operator's login to the executive that runs in ``folder``."""
    return security.find_login("usecase", security.OPERATOR, [folder])


def gone(process: psutil.Process) -> bool:
    try:
        return process.status() == psutil.STATUS_ZOMBIE
    except psutil.NoSuchProcess:
        return True


@contextlib.contextmanager
def executive(folder: Path, endpoint: str) -> Iterator[subprocess.Popen[str]]:
    """``dura run`` on the use case in ``folder``; killed, with its children, at the end."""
    process = subprocess.Popen(
        [sys.executable, "-m", "executive.cli", "run", str(USECASE), "--endpoint", endpoint],
        cwd=folder,
        env={**os.environ, "PYTHONPATH": str(ROOT)},
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    children: list[psutil.Process] = []
    try:
        assert process.stdout is not None
        line = process.stdout.readline()
        assert "runs on" in line, line + process.stderr.read() if process.stderr else ""
        yield process
    finally:
        with contextlib.suppress(psutil.NoSuchProcess):
            children = psutil.Process(process.pid).children(recursive=True)
        if process.poll() is None:
            process.send_signal(signal.SIGTERM)
            try:
                process.wait(30)
            except subprocess.TimeoutExpired:
                process.kill()
                process.wait()
        for child in children:
            with contextlib.suppress(psutil.NoSuchProcess):
                child.kill()
        for stream in (process.stdout, process.stderr):
            if stream is not None:
                stream.close()


def dura_in(folder: Path) -> Callable[..., subprocess.CompletedProcess[str]]:
    return lambda *args: run_dura(*args, cwd=folder)


def pid_of(dura: Callable[..., subprocess.CompletedProcess[str]], name: str) -> int:
    listed = json.loads(dura("component", "list", "--json").stdout)["components"]
    return int(next(c["pid"] for c in listed if c["component"] == name))


def test_component_commands_say_clearly_when_no_executive_runs(
    tmp_path: Path, endpoint: str
) -> None:
    dura = dura_in(tmp_path)
    done = dura("component", "list")
    assert done.returncode == 1
    assert done.stderr.startswith(
        "dura: no executive runs in this folder (no .dura/executive.json)"
    )
    done = dura("component", "start", "lidar", "--robot", str(USECASE), "--endpoint", endpoint)
    assert done.returncode == 1
    assert done.stderr.startswith(f"dura: no executive for robot 'usecase' at {endpoint}")


@pytest.mark.slow
def test_components_are_started_listed_logged_stopped_and_restarted_through_the_cli(
    tmp_path: Path, endpoint: str
) -> None:
    dura = dura_in(tmp_path)
    with executive(tmp_path, endpoint) as process:
        run_file = json.loads((tmp_path / ".dura" / "executive.json").read_text())
        assert run_file["robot"] == "usecase" and run_file["pid"] == process.pid

        started = dura("component", "start", "lidar")
        assert started.returncode == 0, started.stderr
        assert started.stdout.startswith("lidar: ready (pid ")
        listed = json.loads(dura("component", "list", "--json").stdout)["components"]
        assert [c["component"] for c in listed] == list(COMPONENTS)
        assert {c["component"]: c["state"] for c in listed}["lidar"] == "ready"
        table = dura("component", "list").stdout.splitlines()
        assert table[0].split() == ["NAME", "KIND", "HOST", "STATE", "PID", "SINCE", "REASON"]

        logs = dura("component", "logs", "lidar", "--json")
        assert json.loads(logs.stdout)["lines"][0].startswith("--- dura: started lidar")
        assert Path(json.loads(logs.stdout)["path"]) == tmp_path / ".dura" / "logs" / "lidar.log"

        restarted = json.loads(dura("component", "restart", "lidar", "--json").stdout)
        assert restarted["state"] == "ready" and restarted["pid"] != listed[0]["pid"]
        stopped = dura("component", "stop", "lidar")
        assert stopped.stdout == "lidar: stopped (exited with code 0)\n"

        unknown = dura("component", "start", "lidr")
        assert unknown.returncode == 1
        assert unknown.stderr.startswith("dura: no component 'lidr' in robot 'usecase'")

        dura("component", "start", "cam")
        cam = psutil.Process(pid_of(dura, "cam"))
        process.send_signal(signal.SIGINT)
        assert process.wait(30) == 0
        assert gone(cam)
        assert not (tmp_path / ".dura" / "executive.json").exists()
        assert process.stdout is not None
        assert "executive of robot 'usecase' stopped" in process.stdout.read()


@pytest.mark.slow
def test_all_use_case_components_start_through_the_cli_and_publish_at_their_rates(
    tmp_path: Path, endpoint: str
) -> None:
    dura = dura_in(tmp_path)
    with (
        executive(tmp_path, endpoint),
        Bus("usecase", name="test", endpoint=endpoint, login=operator(tmp_path)) as bus,
    ):
        recorders = {name: Recorder(bus, topic(name)) for name in RATES}
        states = Recorder(bus, component("*", "state"))
        for name in COMPONENTS:
            done = dura("component", "start", name)
            assert done.returncode == 0, done.stderr
        for recorder in recorders.values():
            recorder.clear()
        assert wait_for(lambda: recorders["scan"].count() >= 30, 10)
        for name, rate in RATES.items():
            stamps = [m.payload["stamp"] for m in recorders[name].messages]
            measured = (len(stamps) - 1) / (stamps[-1] - stamps[0])
            assert rate * 0.75 < measured < rate * 1.25, (name, measured)

        os.kill(pid_of(dura, "lidar"), signal.SIGKILL)
        assert states.wait(lambda p: p["component"] == "lidar" and p["state"] == "exited")
        reported = ComponentState.from_payload(states.payloads[-1])
        assert (reported.state, reported.signal) == (Lifecycle.EXITED, signal.SIGKILL)


@pytest.mark.slow
def test_sigkill_of_the_executive_takes_all_its_components_with_it(
    tmp_path: Path, endpoint: str
) -> None:
    dura = dura_in(tmp_path)
    with executive(tmp_path, endpoint) as process:
        for name in ("lidar", "lidar_filter", "cam"):
            assert dura("component", "start", name).returncode == 0
        components = {pid_of(dura, name) for name in ("lidar", "lidar_filter", "cam")}
        # every child goes: the three components and the planner's worker
        children = psutil.Process(process.pid).children(recursive=True)
        assert components <= {c.pid for c in children}
        (planner,) = [c for c in children if "executive.planning.planner_worker" in c.cmdline()]
        scratch = Path(planner.environ()["TMPDIR"])  # the engines' temporary files
        assert scratch.is_dir()
        process.kill()
        process.wait()
        assert wait_for(
            lambda: all(gone(c) for c in children), 30
        )  # a bound, not a timing: a loaded machine is slow
        assert wait_for(lambda: not scratch.exists(), 10)


@pytest.mark.slow
def test_faults_are_injected_through_the_cli_and_a_bad_one_is_refused_in_one_line(
    tmp_path: Path, endpoint: str
) -> None:
    dura = dura_in(tmp_path)
    with executive(tmp_path, endpoint):
        assert dura("component", "start", "lidar").returncode == 0
        slow = dura("component", "inject", "lidar", "wrong_rate", "--option", "factor=0.5")
        assert slow.returncode == 0, slow.stderr
        assert slow.stdout.startswith("lidar: wrong_rate injected, factor=0.5 (pid ")
        for bad, reason in (
            (("lidar", "melt"), "unknown fault mode 'melt'"),
            (("lidar", "crash", "--option", "exit_code=x"), "--option must be KEY=NUMBER"),
            (("cam", "crash"), "'cam' is stopped, not running"),
        ):
            refused = dura("component", "inject", *bad)
            assert refused.returncode == 1 and reason in refused.stderr, refused.stderr
            assert len(refused.stderr.splitlines()) == 1
        crashed = dura("component", "inject", "lidar", "crash", "--option", "exit_code=3")
        assert crashed.returncode == 0, crashed.stderr
        assert wait_for(lambda: "exited with code 3" in dura("component", "logs", "lidar").stdout)
        # restarted, the list still says why it ended, and where to read the rest
        listed = dura("component", "list").stdout
        assert "lidar wrote last when it last failed:\n  " in listed
        assert "injected fault: crash" in listed.split("wrote last")[1]


@pytest.mark.slow
def test_monitoring_in_a_process_of_its_own_diagnoses_a_fault_of_the_main_processes_components(
    tmp_path: Path,
) -> None:
    heard: list[dict[str, Any]] = []
    diagnosers: set[str] = set()
    with RobotProcess(USECASE, tmp_path, run_args=["--without", "monitoring"]) as robot:
        argv = [sys.executable, "-m", "executive.cli", "run", str(USECASE), "--only",
                "monitoring", "--endpoint", robot.endpoint, "--db", str(robot.kb_path)]  # fmt: skip
        with subprocess.Popen(
            argv, cwd=tmp_path, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True
        ) as monitoring:
            try:
                assert monitoring.stdout is not None
                lines = [monitoring.stdout.readline() for _ in range(2)]
                assert lines[0].startswith("dura: monitoring of robot 'usecase': connects to")
                assert lines[1] == "dura: monitoring of robot 'usecase': runs\n", lines
                assert wait_for(lambda: robot.bus.alive(service_alive("monitoring")), 10)

                def diagnosis(message: Message) -> None:
                    heard.append(message.payload)
                    diagnosers.add(message.caller_id)

                robot.bus.subscribe(DIAGNOSES, diagnosis)
                live: list[str] = []  # events as they are published
                robot.bus.subscribe(EVENTS, lambda m: live.append(m.payload["kind"]))
                assert robot.request("component/start", {"name": "lidar"})["state"] == "ready"
                robot.request("component/inject", {"name": "lidar", "mode": "stop_publishing"})
                assert wait_for(lambda: any(["lidar"] in d["diagnoses"] for d in heard), 30)
                # the repair rules run there too: the use case's rule restarts lidar
                assert wait_for(lambda: robot.events("RULE_FIRED"), 30)
                assert diagnosers == {"monitoring"}  # none of the executive's own
                assert wait_for(lambda: "RULE_FIRED" in live, 10)  # on the bus, live
            finally:
                monitoring.send_signal(signal.SIGTERM)
                assert monitoring.wait(30) == 0
    main = (tmp_path / "executive.log").read_text()
    assert "dura: executive of robot 'usecase' runs on" in main


def test_a_group_of_services_nobody_knows_is_refused_in_one_line(
    dura: Callable[..., subprocess.CompletedProcess[str]],
) -> None:
    refused = dura("run", str(USECASE), "--only", "everything")
    assert refused.returncode == 2 and "invalid choice: 'everything'" in refused.stderr
    both = dura("run", str(USECASE), "--only", "monitoring", "--without", "monitoring")
    assert both.returncode == 2 and "not allowed with argument" in both.stderr
