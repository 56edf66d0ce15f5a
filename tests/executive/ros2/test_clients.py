"""dura's clients of ROS 2 services, actions and lifecycle nodes against the example's
stand-in nodes (their own rendering of ROS 2's conventions), in one process."""

from __future__ import annotations

import threading
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

from examples.ros2.nodes import interfaces as kit
from examples.ros2.nodes.lidar import Lidar
from examples.ros2.nodes.navigator import Navigator
from examples.ros2.nodes.odometry import Odometry
from examples.ros2.nodes.rosnode import Node
from executive.ros2.action import ActionClient, ActionGoalStatus, CancelReturn
from executive.ros2.lifecycle_node import LifecycleClient
from executive.ros2.participant import Participant
from executive.ros2.service_client import ServiceClient
from executive.ros2.types import TypeLibrary
from knowledge.errors import BusError
from knowledge.ros2_messages import message_store
from tests.conftest import ROOT, wait_for

NAV = "nav2_msgs/action/NavigateToPose"


@pytest.fixture(scope="module")
def library() -> TypeLibrary:
    return TypeLibrary(message_store("jazzy", [ROOT / "examples" / "ros2" / "msgs"]), "jazzy")


@pytest.fixture
def dura(domain: int) -> Iterator[Participant]:
    with Participant(domain, name="dura_test") as participant:
        yield participant


@pytest.fixture
def robot(domain: int, tmp_path: Path) -> Iterator[dict[str, Node]]:
    """The stand-in lidar, odometry and navigator, running."""
    nodes: dict[str, Node] = {
        "lidar": Lidar(domain, rate=20.0),
        "odometry": Odometry(domain, pose_file=tmp_path / "pose.json"),
        "navigator": Navigator(domain, speed=4.0, scan_timeout=2.0),
    }
    try:
        for node in nodes.values():
            node.start()
        yield nodes
    finally:
        for node in nodes.values():
            node.close()


def goal_to(x: float, y: float = 0.0) -> dict[str, Any]:
    return {"pose": {"header": {"frame_id": "map"}, "pose": {"position": {"x": x, "y": y}}}}


def test_a_service_call_gets_its_reply_and_two_clients_never_get_each_others(
    dura: Participant, library: TypeLibrary, robot: dict[str, Node]
) -> None:
    clients = [ServiceClient(dura, library, "/odometry/reset", "std_srvs/srv/Trigger")
               for _ in range(2)]  # fmt: skip
    try:
        assert all(c.wait(5.0) for c in clients)
        futures = [c.call_async() for c in clients for _ in range(3)]
        replies = [f.result(5.0) for f in futures]
        assert all(r == {"success": True, "message": "relocalized at (0.00, 0.00)"}
                   for r in replies)  # fmt: skip
        assert clients[0].guid != clients[1].guid
    finally:
        for client in clients:
            client.close()


def test_a_service_without_a_server_is_not_ready_and_a_call_times_out(
    dura: Participant, library: TypeLibrary
) -> None:
    client = ServiceClient(dura, library, "/nobody/home", "std_srvs/srv/Trigger")
    try:
        assert not client.wait(0.3)
        with pytest.raises(BusError, match=r"/nobody/home did not answer within 0\.2 s"):
            client.call(timeout=0.2)
    finally:
        client.close()


def test_a_managed_node_goes_through_its_states_and_tells_each_transition(
    dura: Participant, library: TypeLibrary, robot: dict[str, Node]
) -> None:
    heard: list[tuple[str, str, str]] = []
    lock = threading.Lock()

    def transition(label: str, start: str, goal: str) -> None:
        with lock:
            heard.append((label, start, goal))

    node = LifecycleClient(dura, library, "/navigator", on_transition=transition)
    try:
        assert node.wait(5.0)
        assert node.state(timeout=10.0) == "unconfigured"
        visited = []
        for command in ("configure", "start", "pause", "resume", "stop"):
            outcome = node.drive(command, timeout=10.0)
            assert outcome is not None and outcome.success, command
            visited.append(outcome.state)
        assert visited == ["inactive", "active", "inactive", "active", "unconfigured"]
        assert node.drive("pause", timeout=10.0) is None  # nothing to do when unconfigured
        refused = node.transition("activate", timeout=10.0)  # not from unconfigured
        assert (refused.success, refused.state) == (False, "unconfigured")
        assert wait_for(lambda: len(heard) == 12)  # each transition and its success
        assert heard[:2] == [("configure", "unconfigured", "configuring"),
                             ("transition_success", "configuring", "inactive")]  # fmt: skip
    finally:
        node.close()


def test_a_failed_configure_leaves_the_node_unconfigured_and_says_so(
    dura: Participant, library: TypeLibrary, domain: int
) -> None:
    navigator = Navigator(domain, fail_configure=True)
    navigator.start()
    node = LifecycleClient(dura, library, "/navigator")
    try:
        assert node.wait(5.0)
        outcome = node.drive("start", timeout=10.0)
        assert outcome is not None
        assert (outcome.transition, outcome.success, outcome.state) == (
            "configure", False, "unconfigured",
        )  # fmt: skip
    finally:
        node.close()
        navigator.close()


@pytest.fixture
def active(dura: Participant, library: TypeLibrary, robot: dict[str, Node]) -> Iterator[None]:
    node = LifecycleClient(dura, library, "/navigator")
    try:
        assert node.wait(5.0)
        node.drive("start", timeout=10.0)
        yield
    finally:
        node.close()


@pytest.fixture
def navigate(
    dura: Participant, library: TypeLibrary, robot: dict[str, Node]
) -> Iterator[ActionClient]:
    client = ActionClient(dura, library, "/navigate_to_pose", NAV)
    try:
        assert client.wait(5.0)
        yield client
    finally:
        client.close()


def test_an_action_goal_streams_feedback_and_succeeds(navigate: ActionClient, active: None) -> None:
    feedback: list[dict[str, Any]] = []
    goal = navigate.send(goal_to(1.0), timeout=2.0, feedback=feedback.append)
    assert goal.accepted
    result = goal.result(10.0)
    assert result is not None and result.status is ActionGoalStatus.SUCCEEDED
    assert result.result == {"error_code": 0, "error_msg": ""}
    assert feedback and feedback[-1]["distance_remaining"] < feedback[0]["distance_remaining"]
    assert set(feedback[0]) == {"current_pose", "navigation_time", "estimated_time_remaining",
                                "number_of_recoveries", "distance_remaining"}  # fmt: skip


def test_an_action_goal_the_server_aborts_ends_aborted_with_the_servers_reason(
    navigate: ActionClient, active: None
) -> None:
    goal = navigate.send(goal_to(500.0), timeout=10.0)
    result = goal.result(5.0)
    assert result is not None and result.status is ActionGoalStatus.ABORTED
    assert result.result == {"error_code": 9000, "error_msg": "outside the map"}


def test_a_cancelled_action_goal_ends_cancelled(navigate: ActionClient, active: None) -> None:
    goal = navigate.send(goal_to(20.0), timeout=10.0)
    assert goal.result(0.3) is None  # still driving
    assert goal.cancel(2.0) is CancelReturn.NONE
    result = goal.result(5.0)
    assert result is not None and result.status is ActionGoalStatus.CANCELED
    assert goal.cancel(2.0) is CancelReturn.GOAL_TERMINATED


def test_an_inactive_navigator_rejects_goals(navigate: ActionClient) -> None:
    goal = navigate.send(goal_to(1.0), timeout=10.0)
    assert not goal.accepted
    assert goal.done()


def test_the_stand_ins_hand_written_types_are_the_ones_dura_builds(library: TypeLibrary) -> None:
    for name, stand_in in (("sensor_msgs/msg/LaserScan", kit.LaserScan),
                           ("nav_msgs/msg/Odometry", kit.Odometry)):  # fmt: skip
        assert library.idl(name).__idl_typename__ == stand_in.__idl_typename__  # type: ignore[attr-defined]
