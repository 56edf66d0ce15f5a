from __future__ import annotations

from executive.tasks.configuration import SystemConfiguration, Transition
from knowledge.description import FunctionalitySpec
from tests.executive.tasks.scheduling_cases import usecase

LIDAR = {"obstacle_scan": "lidar_filter", "laser_scan": "lidar", "base": "robot_base"}
CAM = {"obstacle_scan": "cam_to_lidar", "camera": "cam", "base": "robot_base"}
PICTURE = {"camera": "cam"}


def functionalities() -> list[FunctionalitySpec]:
    return list(usecase()[0].values())


def test_a_first_task_starts_its_functionalities_dependencies_first() -> None:
    target = SystemConfiguration().with_task("1", LIDAR)
    transition = SystemConfiguration().transition(target, functionalities())
    assert transition == Transition(start=("lidar", "lidar_filter", "robot_base"))


def test_the_last_task_stops_its_functionalities_dependents_first() -> None:
    current = SystemConfiguration().with_task("1", LIDAR)
    transition = current.transition(current.without_task("1"), functionalities())
    assert transition == Transition(stop=("robot_base", "lidar_filter", "lidar"))
    assert transition.stop.index("lidar_filter") < transition.stop.index("lidar")


def test_a_configuration_change_keeps_what_both_configurations_use() -> None:
    # scenario 2: lidar is permanently faulty, move_to switches to cam and cam_to_lidar
    current = SystemConfiguration().with_task("1", LIDAR)
    transition = current.transition(current.with_task("1", CAM), functionalities())
    assert transition.stop == ("lidar_filter", "lidar")
    assert transition.start == ("cam", "cam_to_lidar")
    assert transition.keep == {"robot_base"}


def test_a_shared_cam_runs_as_long_as_either_task_needs_it() -> None:
    # scenario 4: move_to on cam_to_lidar and take_picture share cam
    both = SystemConfiguration().with_task("1", CAM).with_task("2", PICTURE)
    assert both.users["cam"] == {"1", "2"}
    picture_done = both.transition(both.without_task("2"), functionalities())
    assert picture_done.empty
    assert picture_done.keep == {"cam", "cam_to_lidar", "robot_base"}
    move_done = both.transition(both.without_task("1"), functionalities())
    assert move_done.stop == ("robot_base", "cam_to_lidar")
    assert move_done.keep == {"cam"}


def test_a_second_task_starts_only_what_does_not_run_yet() -> None:
    current = SystemConfiguration().with_task("1", CAM)
    transition = current.transition(current.with_task("2", PICTURE), functionalities())
    assert transition.empty
    assert current.with_task("2", PICTURE).users == {
        "cam": frozenset({"1", "2"}),
        "cam_to_lidar": frozenset({"1"}),
        "robot_base": frozenset({"1"}),
    }


def test_stopping_and_starting_happen_in_one_transition() -> None:
    # scenario 3: the first move_to ends, the second starts on the same functionalities
    current = SystemConfiguration().with_task("1", LIDAR)
    target = current.without_task("1").with_task("2", LIDAR)
    transition = current.transition(target, functionalities())
    assert transition.empty
    assert target.users["robot_base"] == {"2"}


def test_idle_spares_a_task_takes_resume_consumers_first_and_pause_when_it_lets_go() -> None:
    spare = {"obstacle_scan": "cam_to_lidar", "camera": "cam"}
    waiting = SystemConfiguration({"1": LIDAR}, standby={"standby: cam_to_lidar": spare})
    assert waiting.idle == {"cam", "cam_to_lidar"}
    taken = SystemConfiguration({"1": CAM}, standby={"standby: cam_to_lidar": spare})
    assert taken.idle == frozenset()
    failover = waiting.transition(taken, functionalities())
    assert failover.start == () and failover.stop == ("lidar_filter", "lidar")
    assert failover.resume == ("cam_to_lidar", "cam")  # listening before the images come
    back = taken.transition(waiting, functionalities())
    assert back.pause == ("cam", "cam_to_lidar") and back.start == ("lidar", "lidar_filter")
