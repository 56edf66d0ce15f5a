from __future__ import annotations

from knowledge.availability import Availability, blocked_tasks
from knowledge.description import RobotDescription
from knowledge.robot import load_robot
from tests.conftest import USECASE
from tests.executive.tasks.scheduling_cases import functionality, usecase


def test_every_functionality_is_usable_when_nothing_is_faulty() -> None:
    functionalities, _ = usecase()
    availability = Availability.of(functionalities.values(), ())
    assert availability.usable == set(functionalities)
    assert availability.unusable == {}
    assert availability.explain("obstacle_scan") == ""


def test_a_functionality_on_top_of_a_permanently_faulty_one_is_unusable() -> None:
    functionalities, _ = usecase()
    availability = Availability.of(functionalities.values(), {"lidar"})
    assert availability.unusable == {
        "lidar": "is permanently faulty",
        "lidar_filter": "requires 'laser_scan' (lidar is permanently faulty)",
    }
    assert availability.usable == {"robot_base", "cam", "cam_to_lidar"}
    assert availability.available("obstacle_scan")  # cam_to_lidar still provides it
    assert not availability.available("laser_scan")


def test_an_unavailable_capability_is_explained_through_every_provider() -> None:
    functionalities, _ = usecase()
    availability = Availability.of(functionalities.values(), {"lidar", "cam"})
    assert availability.explain("obstacle_scan") == (
        "no provider for capability 'obstacle_scan': "
        "lidar_filter requires 'laser_scan' (lidar is permanently faulty), "
        "cam_to_lidar requires 'camera' (cam is permanently faulty)"
    )
    assert availability.explain("warp_drive") == (
        "no provider for capability 'warp_drive': no functionality provides it"
    )


def test_unusability_propagates_through_several_levels() -> None:
    chain = [
        functionality("power", ["power"]),
        functionality("lidar", ["laser_scan"], ["power"]),
        functionality("filter", ["obstacle_scan"], ["laser_scan"]),
    ]
    availability = Availability.of(chain, {"power"})
    assert availability.usable == set()
    assert availability.unusable["filter"] == (
        "requires 'laser_scan' (lidar requires 'power' (power is permanently faulty))"
    )


def test_a_cycle_of_requirements_never_runs() -> None:
    loop = [
        functionality("a", ["ca"], ["cb"]),
        functionality("b", ["cb"], ["ca"]),
        functionality("c", ["cc"]),
    ]
    availability = Availability.of(loop, ())
    assert availability.usable == {"c"}
    assert availability.unusable["a"] == "requires 'cb' (b requires 'ca' (a requires itself))"


def test_clearing_a_permanent_fault_makes_what_runs_on_top_of_it_usable_again() -> None:
    functionalities, _ = usecase()
    faulty = Availability.of(functionalities.values(), {"lidar"})
    repaired = Availability.of(functionalities.values(), set())
    assert repaired.usable - faulty.usable == {"lidar", "lidar_filter"}


def test_a_task_is_blocked_when_its_behavior_or_a_capability_it_needs_is_lost() -> None:
    robot = load_robot(USECASE)
    assert blocked_tasks(robot, ()) == {}
    assert blocked_tasks(robot, {"lidar"}) == {}  # cam_to_lidar takes over
    assert blocked_tasks(robot, {"lidar", "cam"}) == {
        "move_to": availability_of(robot, {"lidar", "cam"}).explain("obstacle_scan"),
        "take_picture": "no provider for capability 'camera': cam is permanently faulty",
    }
    assert blocked_tasks(robot, {"take_picture"}) == {
        "take_picture": "behavior take_picture is permanently faulty"
    }


def availability_of(robot: RobotDescription, faulty: set[str]) -> Availability:
    return Availability.of(robot.functionalities.values(), faulty)
