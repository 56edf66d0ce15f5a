"""What ``dura domain show`` tells about a domain: signatures, durations, tasks."""

from __future__ import annotations

from executive.bus.api.planning import DomainAction, DomainSignature, DomainType
from executive.planning.domain_description import describe
from knowledge.domain import read_domain
from knowledge.robot import load_robot
from tests.conftest import USECASE


def test_the_use_case_domain_is_described_with_the_task_of_each_action() -> None:
    robot = load_robot(USECASE)
    reply = describe(read_domain(robot.domain), robot)
    assert reply.name == "usecase"
    assert reply.types == [DomainType("place", "object")]
    assert DomainSignature("connected", ("place", "place")) in reply.predicates
    assert reply.functions == [DomainSignature("travel_time", ("place", "place"))]
    move_to = next(a for a in reply.actions if a.name == "move_to")
    assert move_to == DomainAction(
        name="move_to",
        parameters=(("?from", "place"), ("?to", "place")),
        durative=True,
        duration="(= ?duration (travel_time ?from ?to))",
        task="move_to",
        behavior="move_to",
        goal={"start": "?from", "target": "?to"},
        blocked=None,
    )


def test_an_action_that_cannot_run_now_says_why() -> None:
    robot = load_robot(USECASE)
    reply = describe(read_domain(robot.domain), robot, {"take_picture": "cam is gone"})
    runs = {a.name: a.blocked for a in reply.actions}
    assert runs == {"move_to": None, "take_picture": "cam is gone"}
