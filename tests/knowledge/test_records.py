"""The knowledge base's records: frozen, compared, hashed and shown by their fields; a
fact knows its PDDL text; and the records the test harness returned as dicts before
still read by key, with a warning that names the attribute."""

from __future__ import annotations

import dataclasses

import pytest

from knowledge.records import Event, Fact, Goal, GoalState, Plan, PlanState, PlanStep


def test_a_record_is_frozen_and_compared_hashed_and_shown_by_its_fields() -> None:
    goal = Goal(1, "(robot_at lab)", GoalState.PENDING)
    assert goal == Goal(1, "(robot_at lab)", GoalState.PENDING) != Goal(2, "x", GoalState.PENDING)
    assert len({goal, Goal(1, "(robot_at lab)", GoalState.PENDING)}) == 1
    assert repr(goal).startswith("Goal(id=1, expression='(robot_at lab)', state=<GoalState.")
    with pytest.raises(dataclasses.FrozenInstanceError):
        goal.id = 2  # type: ignore[misc]
    plan = Plan(3, PlanState.PENDING, (PlanStep(0, "move_to", ("dock", "lab"), 0.0),))
    assert dataclasses.replace(plan, engine="kairos").steps == plan.steps


def test_a_fact_knows_its_pddl_text_which_it_is_not_compared_by() -> None:
    assert Fact("robot_at", ("lab",)).text == "(robot_at lab)"
    assert Fact("robot_at", ("lab",), False).text == "(not (robot_at lab))"
    assert Fact("battery", (), 80.0).text == str(Fact("battery", (), 80.0)) == "(= (battery) 80)"
    assert dataclasses.replace(Fact("battery", (), 80.0), value=20.0).text == "(= (battery) 20)"
    assert Fact("a") == Fact("a") and "text" not in repr(Fact("a"))


def test_a_record_read_by_key_warns_and_names_the_attribute() -> None:
    goal = Goal(1, "(robot_at lab)", GoalState.ACHIEVED)
    with pytest.warns(DeprecationWarning, match=r"Goal\['state'\] is deprecated: use \.state"):
        assert goal["state"] == "achieved"  # as JSON, as the dict held it
    event = Event(7, 1.0, "REPAIR", "lidar", {"restart": True})
    with pytest.warns(DeprecationWarning, match=r"Event\['data'\] is deprecated: use \.data"):
        assert event["data"]["restart"] is True
    with pytest.warns(DeprecationWarning, match=r"Event\.get\('subject'\) is deprecated"):
        assert event.get("subject") == "lidar"
    assert event.get("nothing", 5) == 5
    with pytest.raises(KeyError):
        event["nothing"]
