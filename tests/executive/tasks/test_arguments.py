"""A task asked for by hand names objects of the world: unknown objects and objects of
another type are refused with the objects that would fit."""

from __future__ import annotations

import dataclasses

import pytest

from executive.tasks.arguments import check_objects
from knowledge.domain import DomainInfo, read_domain
from knowledge.errors import KnowledgeError
from tests.executive.runtime.rig import USECASE_ROBOT

MOVE = USECASE_ROBOT.tasks["move_to"]
OBJECTS = {"dock": "place", "lab": "place", "office": "place"}


@pytest.fixture(scope="module")
def domain() -> DomainInfo:
    return read_domain(USECASE_ROBOT.domain)


def test_objects_of_the_right_type_and_fields_that_are_no_parameters_pass(
    domain: DomainInfo,
) -> None:
    check_objects(MOVE, {"start": "dock", "target": "lab"}, domain, OBJECTS)
    check_objects(MOVE, {"target": "lab"}, domain, OBJECTS)  # the others stay unset
    check_objects(MOVE, {"speed": "fast"}, domain, OBJECTS)  # not an action parameter


def test_an_unknown_object_is_refused_with_the_objects_that_fit(domain: DomainInfo) -> None:
    with pytest.raises(KnowledgeError) as refused:
        check_objects(MOVE, {"start": "narnia", "target": "lab"}, domain, OBJECTS)
    assert str(refused.value) == (
        "task 'move_to': start=narnia: no object 'narnia' of type 'place' (objects of that "
        "type: dock, lab, office)"
    )
    with pytest.raises(KnowledgeError, match="no object 3 of type 'place'"):
        check_objects(MOVE, {"target": 3}, domain, OBJECTS)


def test_an_object_of_another_type_is_refused(domain: DomainInfo) -> None:
    typed = dataclasses.replace(domain, supertypes={**domain.supertypes, "robot": None})
    with pytest.raises(KnowledgeError, match="'r2' is a robot, not of type 'place'"):
        check_objects(MOVE, {"target": "r2"}, typed, {**OBJECTS, "r2": "robot"})
    subtyped = dataclasses.replace(domain, supertypes={**domain.supertypes, "room": "place"})
    check_objects(MOVE, {"target": "kitchen"}, subtyped, {**OBJECTS, "kitchen": "room"})
