"""Shared planning cases and fixtures: the example domains, a warm Kairos planner, a
knowledge base seeded with a robot's world.

Import the fixtures by their function names (``kairos_fixture`` ...); tests use them
by fixture name (``kairos`` ...).
"""

from __future__ import annotations

import functools
from collections.abc import Iterator
from pathlib import Path

import pytest

from executive.planning.expression import Expression, Signature, parse
from executive.planning.goals import GoalSpec
from executive.planning.planner import Planner, PlanningTask
from executive.planning.problem import World, read_world
from knowledge.domain import DomainInfo, read_domain
from knowledge.knowledge_base import KnowledgeBase
from tests.conftest import ROOT

USECASE_DOMAIN = ROOT / "domains" / "usecase" / "domain.pddl"
USECASE_PROBLEM = ROOT / "examples" / "usecase" / "problem.pddl"
TRANSPORT_DOMAIN = ROOT / "domains" / "transport" / "domain.pddl"
TRANSPORT_PROBLEM = ROOT / "examples" / "transport" / "problem.pddl"
TRANSPORT = ROOT / "examples" / "transport" / "robot.yaml"

# A classical (non-temporal) domain for Fast Downward.
CLASSICAL_DOMAIN = """(define (domain rooms) (:requirements :strips :typing)
  (:types room)
  (:predicates (at ?r - room) (door ?a ?b - room) (visited ?r - room))
  (:action go :parameters (?a ?b - room)
    :precondition (and (at ?a) (door ?a ?b))
    :effect (and (not (at ?a)) (at ?b) (visited ?b))))
"""
CLASSICAL_PROBLEM = """(define (problem tour) (:domain rooms)
  (:objects a b c - room)
  (:init (at a) (door a b) (door b c) (door c a))
  (:goal (and (visited c) (at a))))
"""


@functools.cache
def world(domain: Path, problem: Path) -> World:
    return read_world(domain, problem)[0]


@functools.cache
def signature(domain: Path = USECASE_DOMAIN, problem: Path = USECASE_PROBLEM) -> Signature:
    return Signature.of(read_domain(domain), world(domain, problem).objects)


def expr(text: str, domain: Path = USECASE_DOMAIN, problem: Path = USECASE_PROBLEM) -> Expression:
    return parse(text, signature(domain, problem))


def usecase_task(*goals: tuple[str, dict[str, float]] | str) -> PlanningTask:
    """A planning task on the use-case world; a goal is text or (text, {priority, deadline})."""
    specs = []
    for i, g in enumerate(goals, 1):
        text, extra = (g, {}) if isinstance(g, str) else g
        specs.append(GoalSpec(i, expr(text), int(extra.get("priority", 0)), extra.get("deadline")))
    return PlanningTask(USECASE_DOMAIN, world(USECASE_DOMAIN, USECASE_PROBLEM), tuple(specs))


@pytest.fixture(scope="module", name="kairos")
def kairos_fixture() -> Iterator[Planner]:
    """One warm Kairos worker per test module (small timeout: the cases are small)."""
    with Planner("kairos", timeout=10.0) as planner:
        planner.start(USECASE_DOMAIN)
        yield planner


@pytest.fixture(name="usecase_kb")
def usecase_kb_fixture(tmp_path: Path) -> Iterator[KnowledgeBase]:
    """A knowledge base holding the use-case world."""
    from executive.planning.problem import seed_world
    from knowledge.robot import load_robot

    with KnowledgeBase(tmp_path / "usecase.db") as kb:
        seed_world(kb, load_robot(ROOT / "examples" / "usecase" / "robot.yaml"))
        yield kb


@functools.cache
def usecase_domain() -> DomainInfo:
    return read_domain(USECASE_DOMAIN)


# A domain with what `dura domain check` warns about, line by line (see its test).
FLAWED_DOMAIN = """(define (domain flawed)
  (:requirements :strips :typing :durative-actions :negative-preconditions)
  (:types place robot gadget)
  (:predicates
    (at ?r - robot ?p - place)
    (road ?a ?b - place)
    (charged ?r - robot)
    (door_open ?p - place)
    (painted ?p - place)
    (visited ?p - place))
  (:durative-action drive
    :parameters (?r - robot ?a ?b - place)
    :duration (= ?duration 5)
    :condition (and (at start (at ?r ?a)) (at start (charged ?r)) (over all (road ?a ?b)))
    :effect (and (at start (not (at ?r ?a))) (at start (not (charged ?r))) (at end (at ?r ?b))))
  (:durative-action enter
    :parameters (?r - robot ?p - place)
    :duration (= ?duration 1)
    :condition (and (at start (at ?r ?p)) (at start (door_open ?p)))
    :effect (at end (visited ?p))))
"""
FLAWED_PROBLEM = """(define (problem tour) (:domain flawed)
  (:objects r1 - robot a b c - place)
  (:init (at r1 a) (charged r1) (road a b))
  (:goal (and (visited b) (at r1 c))))
"""

# ROSPlan's test problems name objects like their types (`driver - driver`).
DRIVERLOG_DOMAIN = """(define (domain driverlog)
  (:requirements :typing :durative-actions)
  (:types driver truck location)
  (:predicates
    (at ?d - driver ?l - location)
    (truck_at ?t - truck ?l - location)
    (driving ?d - driver ?t - truck)
    (link ?a ?b - location))
  (:durative-action board
    :parameters (?d - driver ?t - truck ?l - location)
    :duration (= ?duration 1)
    :condition (and (at start (at ?d ?l)) (over all (truck_at ?t ?l)))
    :effect (and (at start (not (at ?d ?l))) (at end (driving ?d ?t))))
  (:durative-action drive
    :parameters (?d - driver ?t - truck ?a ?b - location)
    :duration (= ?duration 5)
    :condition (and (over all (driving ?d ?t)) (at start (truck_at ?t ?a))
                    (over all (link ?a ?b)))
    :effect (and (at start (not (truck_at ?t ?a))) (at end (truck_at ?t ?b)))))
"""
DRIVERLOG_PROBLEM = """(define (problem drive1) (:domain driverlog)
  (:objects
    driver - driver
    truck - truck
    depot market - location)
  (:init (at driver depot) (truck_at truck depot) (link depot market))
  (:goal (truck_at truck market)))
"""
# the same object declared twice is still refused, at the second declaration (line 6)
DRIVERLOG_TWICE = DRIVERLOG_PROBLEM.replace(
    "depot market - location)", "depot market - location\n    depot - location)"
)
