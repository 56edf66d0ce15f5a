"""ROS 2 programs as components: the launcher starts the example's stand-in nodes under
their hosts, and the hosts carry dura's commands and goals to them over ROS 2.

Every component here is a real process pair (host and program) in this test process's
DDS domain; the test watches the nodes from a participant of its own.
"""

from __future__ import annotations

import dataclasses
import signal
import threading
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import psutil
import pytest

from executive.bus.states import GoalStatus, Lifecycle
from executive.ros2.lifecycle_node import LifecycleClient
from executive.ros2.names import dds_topic
from executive.ros2.participant import Participant
from executive.ros2.qos import ACTION_STATUS, dds_qos
from executive.ros2.types import TypeLibrary
from knowledge.description import RobotDescription
from knowledge.robot import read_robot
from knowledge.ros2_messages import message_store
from tests.conftest import ROOT, wait_for
from tests.executive.runtime.rig import Rig, rig

EXAMPLE = ROOT / "examples" / "ros2" / "robot.yaml"
CANCELED = 5  # action_msgs/msg/GoalStatus


def example(domain: int, folder: Path, **params: dict[str, Any]) -> RobotDescription:
    """The example robot in this test's domain; ``params`` change components' parameters."""
    found, findings = read_robot(EXAMPLE)
    assert found is not None and found.ros2 is not None, findings
    changed = {"odometry": {"pose_file": str(folder / "pose.json")}, **params}

    def adjusted(spec: Any) -> Any:
        extra = changed.get(spec.name)
        return dataclasses.replace(spec, params={**spec.params, **extra}) if extra else spec

    return dataclasses.replace(
        found,
        ros2=dataclasses.replace(found.ros2, domain_id=domain),
        functionalities={n: adjusted(s) for n, s in found.functionalities.items()},
        behaviors={n: adjusted(s) for n, s in found.behaviors.items()},
    )


@pytest.fixture
def watcher(domain: int) -> Iterator[Participant]:
    with Participant(domain, name="test_watcher") as participant:
        yield participant


@pytest.fixture(scope="module")
def library() -> TypeLibrary:
    return TypeLibrary(message_store("jazzy", [ROOT / "examples" / "ros2" / "msgs"]), "jazzy")


def program_of(pid: int | None) -> psutil.Process:
    """The ROS 2 program under its host."""
    assert pid is not None
    [child] = psutil.Process(pid).children()
    return child


def test_a_ros2_node_is_ready_once_it_is_in_the_graph_and_stops_with_its_program(
    endpoint: str, tmp_path: Path, domain: int
) -> None:
    with rig(example(domain, tmp_path), endpoint, tmp_path) as r:
        state = r.launcher.start("lidar")
        assert state.state is Lifecycle.READY, state.reason
        program = program_of(state.pid)
        assert "nodes.lidar" in " ".join(program.cmdline())
        assert program.environ()["ROS_DOMAIN_ID"] == str(domain)
        assert r.launcher.stop("lidar").exit_code == 0
        assert not program.is_running()


def test_a_ros2_node_that_crashes_takes_its_host_along(
    endpoint: str, tmp_path: Path, domain: int
) -> None:
    with rig(example(domain, tmp_path), endpoint, tmp_path) as r:
        program_of(r.launcher.start("lidar").pid).send_signal(signal.SIGKILL)
        assert wait_for(lambda: r.launcher.state("lidar").state is Lifecycle.EXITED)
        assert r.launcher.state("lidar").signal == signal.SIGKILL


def test_a_managed_node_is_driven_through_its_lifecycle_by_dura_s_commands(
    endpoint: str, tmp_path: Path, domain: int, watcher: Participant, library: TypeLibrary
) -> None:
    node = LifecycleClient(watcher, library, "/navigator")
    try:
        with rig(example(domain, tmp_path), endpoint, tmp_path) as r:
            assert r.launcher.start("navigator").state is Lifecycle.READY
            assert node.wait(5.0)
            assert node.state(timeout=10.0) == "active"
            r.launcher.pause("navigator")
            assert node.state(timeout=10.0) == "inactive"
            r.launcher.resume("navigator")
            assert node.state(timeout=10.0) == "active"
            seen: list[str] = []
            stopping = threading.Thread(target=lambda: r.launcher.stop("navigator"))
            stopping.start()
            assert wait_for(lambda: _state(node, seen) == "unconfigured" or not stopping.is_alive())
            stopping.join()
            assert r.launcher.state("navigator").exit_code == 0
            log = "\n".join(r.launcher.logs("navigator"))
            assert "managed node /navigator is inactive" in log  # configured
            assert "managed node /navigator is unconfigured" in log  # cleaned up
    finally:
        node.close()


def _state(node: LifecycleClient, seen: list[str]) -> str:
    try:
        seen.append(node.state(timeout=0.5))
    except Exception:
        return ""
    return seen[-1]


def test_a_refused_configure_is_a_failed_start_with_the_reason(
    endpoint: str, tmp_path: Path, domain: int
) -> None:
    robot = example(domain, tmp_path, navigator={"fail_configure": True})
    with rig(robot, endpoint, tmp_path) as r:
        state = r.launcher.start("navigator")
        assert state.state is Lifecycle.FAILED
        assert "managed node /navigator refused to configure (it is unconfigured)" in state.reason


def test_a_managed_node_that_leaves_its_state_on_its_own_is_a_fault(
    endpoint: str, tmp_path: Path, domain: int, watcher: Participant, library: TypeLibrary
) -> None:
    node = LifecycleClient(watcher, library, "/navigator")
    try:
        with rig(example(domain, tmp_path), endpoint, tmp_path) as r:
            assert r.launcher.start("navigator").state is Lifecycle.READY
            assert node.wait(5.0)
            assert node.transition("deactivate", timeout=10.0).success  # not dura's doing
            assert wait_for(lambda: r.launcher.state("navigator").state is Lifecycle.EXITED)
            assert r.launcher.state("navigator").exit_code == 1
            assert any("went inactive on its own" in line for line in r.launcher.logs("navigator"))
    finally:
        node.close()


# --- behaviors: action goals and service calls ------------------------------------------


@pytest.fixture
def driving(endpoint: str, tmp_path: Path, domain: int) -> Iterator[Rig]:
    """The example robot with lidar, odometry and the navigator running."""
    robot = example(domain, tmp_path, navigator={"speed": 2.0})
    with rig(robot, endpoint, tmp_path) as r:
        for name in ("lidar", "odometry", "navigator", "navigate"):
            state = r.launcher.start(name)
            assert state.state is Lifecycle.READY, (name, state.reason)
        yield r


def goal_to(x: float) -> dict[str, Any]:
    return {"pose.header.frame_id": "map", "pose.pose": {"position": {"x": x}}}


def test_an_action_task_succeeds_with_the_servers_feedback_and_result(driving: Rig) -> None:
    handle = driving.launcher.send_goal("navigate", goal_to(1.0))
    feedback: list[dict[str, Any]] = []
    handle.add_feedback_listener(feedback.append)
    result = handle.wait(20.0)
    assert result is not None and result.status is GoalStatus.SUCCEEDED, result
    assert result.value == {"status": "succeeded", "result": {"error_code": 0, "error_msg": ""}}
    assert feedback and "distance_remaining" in feedback[-1]


def test_an_action_task_the_server_aborts_fails_with_the_servers_reason(driving: Rig) -> None:
    result = driving.launcher.send_goal("navigate", goal_to(500.0)).wait(20.0)
    assert result is not None and result.status is GoalStatus.FAILED
    assert result.reason == (
        "/navigate_to_pose aborted the goal (error_code=9000, error_msg='outside the map')"
    )


def test_a_paused_action_task_cancels_its_ros2_goal_and_sends_it_again_on_resume(
    driving: Rig, watcher: Participant, library: TypeLibrary
) -> None:
    statuses: list[int] = []
    decode = library.decoder("action_msgs/msg/GoalStatusArray")

    def heard(samples: list[Any], received: float) -> None:
        for data, info in samples:
            if info.valid_data:
                statuses.extend(s["status"] for s in decode(data)["status_list"])

    watcher.reader(
        dds_topic("/navigate_to_pose/_action/status"),
        library.idl("action_msgs/msg/GoalStatusArray"),
        dds_qos(ACTION_STATUS),
        heard,
    )
    handle = driving.launcher.send_goal("navigate", goal_to(6.0))
    assert wait_for(lambda: handle.feedback)  # on its way
    driving.launcher.pause("navigate")
    assert wait_for(lambda: CANCELED in statuses)
    assert not handle.done()
    driving.launcher.resume("navigate")
    result = handle.wait(20.0)
    assert result is not None and result.status is GoalStatus.SUCCEEDED, result
    log = "\n".join(driving.launcher.logs("navigate"))
    assert log.count("/navigate_to_pose accepted goal") == 2
    assert "cancelled for the pause; sent again" in log


def test_a_cancelled_action_task_cancels_its_ros2_goal(driving: Rig) -> None:
    handle = driving.launcher.send_goal("navigate", goal_to(30.0))
    assert wait_for(lambda: handle.feedback)
    handle.cancel()
    result = handle.wait(10.0)
    assert result is not None and result.status is GoalStatus.CANCELLED
    # the server's goal has ended with dura's: the navigator takes the next one
    follow_up = driving.launcher.send_goal("navigate", goal_to(0.5)).wait(20.0)
    assert follow_up is not None and follow_up.status is GoalStatus.SUCCEEDED, follow_up


def test_a_service_task_succeeds_with_the_response_or_fails_with_its_message(
    endpoint: str, tmp_path: Path, domain: int
) -> None:
    for lost, expected in ((False, GoalStatus.SUCCEEDED), (True, GoalStatus.FAILED)):
        robot = example(domain, tmp_path, odometry={"lost": lost})
        with rig(robot, endpoint, tmp_path) as r:
            for name in ("odometry", "relocalize"):
                assert r.launcher.start(name).state is Lifecycle.READY
            result = r.launcher.send_goal("relocalize", {}).wait(10.0)
        assert result is not None and result.status is expected, result
        if lost:
            assert result.reason == "/odometry/reset: no match with the map"
        else:
            assert result.value["response"]["success"] is True


def test_a_behavior_whose_server_is_missing_fails_to_start_with_the_reason(
    endpoint: str, tmp_path: Path, domain: int
) -> None:
    robot = example(domain, tmp_path)
    behavior = dataclasses.replace(robot.behaviors["navigate"], startup_timeout=8.0)
    assert behavior.ros2 is not None and behavior.ros2.call is not None
    call = dataclasses.replace(behavior.ros2.call, wait=0.5)
    behavior = dataclasses.replace(behavior, ros2=dataclasses.replace(behavior.ros2, call=call))
    robot = dataclasses.replace(robot, behaviors={**robot.behaviors, "navigate": behavior})
    with rig(robot, endpoint, tmp_path) as r:
        state = r.launcher.start("navigate")
    assert state.state is Lifecycle.FAILED
    assert "ROS 2 action /navigate_to_pose has no server" in state.reason
