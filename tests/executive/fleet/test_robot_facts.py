"""A robot's own facts follow into the fleet's world, and a robot's availability follows
its executive and its steps."""

from __future__ import annotations

import re

import pytest

from executive.fleet.availability import NOT_SEEN, Availability
from executive.fleet.robot_facts import FactMapping, RobotFacts
from knowledge.errors import ConfigError
from knowledge.records import Fact


def test_a_robots_fact_becomes_the_fleets_fact_of_that_robot() -> None:
    where = FactMapping.read("(robot_at ?p)", "(at ?robot ?p)")
    assert where.to_fleet(Fact("robot_at", ("lab",)), "r1") == Fact("at", ("r1", "lab"))
    assert where.to_fleet(Fact("hands_free"), "r1") is None
    battery = FactMapping.read("(battery_level)", "(battery ?robot)")
    assert battery.to_fleet(Fact("battery_level", (), 80.0), "r2") == Fact("battery", ("r2",), 80.0)
    assert where.ours(Fact("at", ("r1", "dock")), "r1")
    assert not where.ours(Fact("at", ("r2", "dock")), "r1")


@pytest.mark.parametrize(
    ("robot", "fleet", "reason"),
    [
        ("robot_at ?p", "(at ?robot ?p)", "is not an atom"),
        ("(robot_at ?p)", "(at ?p)", "does not name the robot (?robot)"),
        ("(robot_at)", "(at ?robot ?p)", "names ?p, which '(robot_at)' does not"),
    ],
)
def test_a_mapping_that_cannot_be_followed_is_refused(robot: str, fleet: str, reason: str) -> None:
    with pytest.raises(ConfigError, match=re.escape(reason)):
        FactMapping.read(robot, fleet)


def test_the_fleets_facts_of_a_robot_follow_its_own_when_it_changes_them() -> None:
    robot = [Fact("robot_at", ("lab",)), Fact("battery_level", (), 75.0)]
    fleet = [Fact("at", ("r1", "dock")), Fact("at", ("r2", "dock")), Fact("battery", ("r1",), 90.0)]
    changes: list[tuple[str, bool]] = []

    def change(text: str, unset: bool) -> None:
        changes.append((text, unset))

    facts = RobotFacts(
        [
            FactMapping.read("(robot_at ?p)", "(at ?robot ?p)"),
            FactMapping.read("(battery_level)", "(battery ?robot)"),
        ],
        "r1",
        ask=lambda name: [f for f in robot if f.name == name],
        fleet_facts=lambda name: [f for f in fleet if f.name == name],
        change=change,
    )
    facts.start()
    facts.heard("STATE_SET", "(robot_at lab)")
    facts.heard("STATE_SET", "(= (battery_level) 75)")
    facts.heard("TASK_STARTED", "(robot_at lab)")  # no change of facts: nothing follows
    facts.stop()
    assert changes == [
        ("(at r1 dock)", True),
        ("(at r1 lab)", False),
        ("(= (battery r1) 75)", False),
    ]
    # when the robot joins, every mapping is followed (here: its battery changed since)
    fleet[:] = [Fact("at", ("r1", "lab")), Fact("battery", ("r1",), 75.0)]
    robot[1] = Fact("battery_level", (), 60.0)
    changes.clear()
    facts.start()
    facts.joined()
    facts.stop()
    assert changes == [("(= (battery r1) 60)", False)]


def test_a_robot_is_available_while_its_executive_is_there_and_its_steps_do_not_keep_failing() -> (
    None
):
    told: list[tuple[str, bool]] = []
    robots = Availability(
        {"r1": "r1", "r2": "r2"}, 2, lambda r, ok, why: told.append((r, ok)), outside={"r3"}
    )
    assert robots.reason("r1") == NOT_SEEN
    assert robots.unavailable_objects() == {"r1", "r2", "r3"}
    robots.joined("r1")
    robots.joined("r2")
    assert robots.unavailable_objects() == {"r3"}
    robots.step_failed("r1", "gripper jammed")
    robots.step_succeeded("r1")  # a success in between: not in a row
    robots.step_failed("r1", "gripper jammed")
    assert robots.reason("r1") is None
    robots.step_failed("r1", "gripper jammed")
    assert robots.reason("r1") == "its last 2 steps failed, the last because gripper jammed"
    robots.lost("r2", "its executive vanished")
    assert robots.unavailable_objects() == {"r1", "r2", "r3"}
    robots.joined("r1")  # its executive joined again: its failures are forgotten
    assert robots.reason("r1") is None
    assert told == [("r1", True), ("r2", True), ("r1", False), ("r2", False), ("r1", True)]
