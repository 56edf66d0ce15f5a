"""Shared planning cases and fixtures: the example domains, a warm Kairos planner, a
knowledge base seeded with a robot's world.

Import the fixtures by their function names (``kairos_fixture`` ...); tests use them
by fixture name (``kairos`` ...).
"""

from __future__ import annotations

import functools
import shutil
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

# A type hierarchy three levels deep (robot -> vehicle -> locatable, fragile -> crate ->
# locatable) with objects named like their types (`robot - robot`, `dock - dock`).
WAREHOUSE_DOMAIN = """; A warehouse robot: actions want supertypes, objects are of subtypes.
(define (domain warehouse)
  (:requirements :strips :typing :durative-actions)
  (:types
    vehicle crate - locatable
    robot truck - vehicle
    fragile - crate
    dock - place)
  (:predicates
    (at ?x - locatable ?p - place)
    (road ?from ?to - place)
    (holding ?v - robot ?c - crate)
    (free ?v - robot)
    (battery_low))
  (:durative-action drive
    :parameters (?v - vehicle ?from ?to - place)
    :duration (= ?duration 5)
    :condition (and (at start (at ?v ?from)) (over all (road ?from ?to)))
    :effect (and (at start (not (at ?v ?from))) (at end (at ?v ?to))))
  (:durative-action pick
    :parameters (?v - robot ?c - crate ?p - place)
    :duration (= ?duration 3)
    :condition (and (over all (at ?v ?p)) (at start (at ?c ?p)) (at start (free ?v)))
    :effect (and (at start (not (at ?c ?p))) (at start (not (free ?v)))
                 (at end (holding ?v ?c))))
  (:durative-action drop
    :parameters (?v - robot ?c - crate ?p - place)
    :duration (= ?duration 2)
    :condition (and (over all (at ?v ?p)) (at start (holding ?v ?c)))
    :effect (and (at start (not (holding ?v ?c))) (at end (at ?c ?p)) (at end (free ?v))))
  (:durative-action charge
    :parameters (?v - robot ?p - dock)
    :duration (= ?duration 10)
    :condition (over all (at ?v ?p))
    :effect (at end (not (battery_low)))))
"""
WAREHOUSE_PROBLEM = """(define (problem hall) (:domain warehouse)
  (:objects
    robot - robot
    dock - dock
    store lab - place
    parcel - crate)
  (:init
    (at robot dock) (free robot) (at parcel store)
    (road dock store) (road store dock) (road store lab) (road lab store))
  (:goal (at parcel lab)))
"""
WAREHOUSE_ROBOT = """# The warehouse robot: the transport example's components on a domain with subtypes.
robot: warehouse
domain: domain.pddl
problem: problem.pddl
integrity: [integrity.yaml]
planner: {engine: kairos, timeout: 30}
sensing:
  - {name: battery_low, topic: battery, field: level, fact: (battery_low), below: 20,
     clear_above: 30}
functionalities:
  lidar: {command: [python, -m, components.lidar], provides: [laser_scan],
          publishes: [scan]}
  localization: {command: [python, -m, components.localization], requires: [laser_scan],
                 provides: [pose], subscribes: [scan, odom], publishes: [pose]}
  base: {command: [python, -m, components.base], provides: [motion],
         subscribes: [cmd_vel, charge], publishes: [odom, battery], shareable: false}
  gripper: {command: [python, -m, components.gripper], provides: [grip],
            subscribes: [grip_cmd], publishes: [grip_state], shareable: false}
behaviors:
  drive_to: {command: [python, -m, components.drive_to], requires: [pose, motion],
             subscribes: [pose], publishes: [cmd_vel]}
  pick: {command: [python, -m, components.pick], requires: [grip, pose],
         subscribes: [grip_state, pose], publishes: [grip_cmd]}
  drop: {command: [python, -m, components.drop], requires: [grip, pose],
         subscribes: [grip_state, pose], publishes: [grip_cmd]}
  dock_and_charge: {command: [python, -m, components.dock_and_charge],
                    requires: [motion, pose], subscribes: [battery, pose],
                    publishes: [cmd_vel, charge]}
tasks:
  drive: {behavior: drive_to, goal: {start: "?from", target: "?to"}}
  pick: {behavior: pick, goal: {crate: "?c", place: "?p"}}
  drop: {behavior: drop, goal: {crate: "?c", place: "?p"}}
  charge: {behavior: dock_and_charge, goal: {dock: "?p"}}
"""
WAREHOUSE_INTEGRITY = """goals:
  - name: recharge
    when: {condition: "(battery_low)"}
    goal: "(and (not (battery_low)) (at robot dock))"
    priority: 100
"""


def warehouse_robot(folder: Path) -> Path:
    """Write the warehouse robot (its description, domain, problem, integrity goals and
    the transport example's components) into ``folder``; the description's path."""
    folder.mkdir(parents=True, exist_ok=True)
    shutil.copytree(TRANSPORT.parent / "components", folder / "components", dirs_exist_ok=True)
    for name, text in (
        ("domain.pddl", WAREHOUSE_DOMAIN),
        ("problem.pddl", WAREHOUSE_PROBLEM),
        ("integrity.yaml", WAREHOUSE_INTEGRITY),
        ("robot.yaml", WAREHOUSE_ROBOT),
    ):
        (folder / name).write_text(text)
    return folder / "robot.yaml"
